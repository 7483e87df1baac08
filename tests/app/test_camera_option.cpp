// The viewer's --camera option: YAW,PITCH[,DISTANCE] parsed, and every malformed value refused with the option named.
#include <gtest/gtest.h>

#include <string>

#include "host/app/camera_option.h"
#include "model/input_error.h"

namespace inc {
namespace {

std::string errorOf(const std::string& text) {
  try {
    parseCameraAngles(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(CameraOption, ParsesAnglesAndOptionalDistance) {
  const CameraAngles a = parseCameraAngles("30,-15.5");
  EXPECT_DOUBLE_EQ(a.yaw_deg, 30.0);
  EXPECT_DOUBLE_EQ(a.pitch_deg, -15.5);
  EXPECT_DOUBLE_EQ(a.distance_m, 0.0);
  EXPECT_DOUBLE_EQ(parseCameraAngles("-400,89,0.35").distance_m, 0.35);
}

TEST(CameraOption, MalformedValuesAreRefusedWithTheOptionNamed) {
  for (const char* bad : {"", "30", "30,20,1,2", "a,20", "30,,1", "30,20,", "nan,20", "30,inf", "30,90", "30,-89.5",
                          "30,20,-0.1", "30 ,20x"}) {
    const std::string e = errorOf(bad);
    EXPECT_NE(e.find("--camera"), std::string::npos) << "\"" << bad << "\": " << e;
  }
  EXPECT_NE(errorOf("30,95").find("[-89, 89]"), std::string::npos);
  EXPECT_NE(errorOf("30,20,-1").find(">= 0"), std::string::npos);
}

}  // namespace
}  // namespace inc
