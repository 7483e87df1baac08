// Tests of the scene keys of the cutting force model (material.cutting): values reach the model, bad ones are refused.
#include <gtest/gtest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "host/haptics/cutting_force_model.h"
#include "host/input_error.h"
#include "host/scene_loader.h"

namespace inc {
namespace {

const char* kFile = "scenes/cut_thresholds.json";

nlohmann::json sceneWithCutting(const nlohmann::json& cutting) {
  nlohmann::json j = nlohmann::json::parse(R"({"geometry": {"kind": "box"}, "models": {"mls": true, "haptics": true}})");
  j["material"]["cutting"] = cutting;
  return j;
}

// Parses expecting an InputError naming kFile, exactly `key`, and a reason containing `part`.
void expectRefused(const std::string& text, const std::string& key, const std::string& part) {
  try {
    parseScene(text, kFile, ".");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), kFile) << e.what();
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_NE(e.reason().find(part), std::string::npos) << e.what();
  }
}

TEST(HapticScene, CutThresholdsAreReadAndDriveTheModel) {
  const Scene s = parseScene(sceneWithCutting({{"press_threshold_n", 2.5},
                                               {"static_friction_n", 1.25},
                                               {"dynamic_friction_n", 0.5},
                                               {"friction_n_per_m", 400.0}})
                                 .dump(),
                             kFile, ".");
  EXPECT_EQ(s.material.cutting.press_n, 2.5);
  EXPECT_EQ(s.material.cutting.static_n, 1.25);
  EXPECT_EQ(s.material.cutting.dynamic_n, 0.5);
  EXPECT_EQ(s.material.cutting.friction_per_depth_n_per_m, 400.0);
  // The model uses the scene's values: a normal force of 2 N (< F_p = 2.5 N) does not let the blade in, so
  // a tangential 1.3 N (> F_s) does not cut; 2.6 N does, then 1.3 N cuts; 0.6 N (in the band) keeps cutting
  // with friction 400 N/m x 2 mm = 0.8 N; 0.49 N (< F_d) stops.
  CuttingForceModel m(s.material.cutting, s.file);
  const Vec3d n{0, 0, 1}, v{0.01, 0, 0};
  EXPECT_EQ(m.tick({1.3, 0, -2.0}, n, v, 2e-3).machine.state, CutState::kPressing);
  EXPECT_EQ(m.tick({0.0, 0, -2.6}, n, v, 2e-3).machine.state, CutState::kPressing);
  EXPECT_EQ(m.tick({1.3, 0, -2.6}, n, v, 2e-3).machine.state, CutState::kCutting);
  const CutForceOutput band = m.tick({0.6, 0, -2.6}, n, v, 2e-3);
  EXPECT_EQ(band.machine.state, CutState::kCutting);
  EXPECT_NEAR(band.friction_n.x, -0.8, 1e-12);
  EXPECT_EQ(m.tick({0.49, 0, -2.6}, n, v, 2e-3).machine.state, CutState::kStopped);
}

TEST(HapticScene, CutThresholdsDefaultAndRoundTrip) {
  const Scene d = parseScene(R"({"geometry": {"kind": "box"}, "models": {"mls": true}})", kFile, ".");
  const CutThresholds<double> def;
  EXPECT_EQ(d.material.cutting.press_n, def.press_n);
  EXPECT_EQ(d.material.cutting.static_n, def.static_n);
  EXPECT_EQ(d.material.cutting.dynamic_n, def.dynamic_n);
  EXPECT_EQ(d.material.cutting.friction_per_depth_n_per_m, def.friction_per_depth_n_per_m);
  // Partial object: the others keep their defaults. Written and read back exactly (1/3 N has no short form).
  const Scene s = parseScene(sceneWithCutting({{"static_friction_n", 1.0 / 3.0}, {"press_threshold_n", 0.0}}).dump(),
                             kFile, ".");
  EXPECT_EQ(s.material.cutting.static_n, 1.0 / 3.0);
  EXPECT_EQ(s.material.cutting.press_n, 0.0);
  EXPECT_EQ(s.material.cutting.dynamic_n, def.dynamic_n);
  const Scene r = parseScene(sceneToJson(s), kFile, ".");
  EXPECT_EQ(r.material.cutting.press_n, s.material.cutting.press_n);
  EXPECT_EQ(r.material.cutting.static_n, s.material.cutting.static_n);
  EXPECT_EQ(r.material.cutting.dynamic_n, s.material.cutting.dynamic_n);
  EXPECT_EQ(r.material.cutting.friction_per_depth_n_per_m, s.material.cutting.friction_per_depth_n_per_m);
}

TEST(HapticScene, BadCutThresholdsNameFileAndKey) {
  const std::string k = "material.cutting.";
  // NaN: as a JSON literal (not JSON) and as a string.
  expectRefused(R"({"geometry": {"kind": "box"}, "models": {"mls": true},
                    "material": {"cutting": {"static_friction_n": NaN}}})",
                k + "static_friction_n", "NaN");
  expectRefused(sceneWithCutting({{"dynamic_friction_n", "nan"}}).dump(), k + "dynamic_friction_n", "NaN");
  // Negative values.
  expectRefused(sceneWithCutting({{"press_threshold_n", -0.1}}).dump(), k + "press_threshold_n", ">= 0");
  expectRefused(sceneWithCutting({{"static_friction_n", -1.0}}).dump(), k + "static_friction_n", "> 0");
  expectRefused(sceneWithCutting({{"dynamic_friction_n", -0.2}}).dump(), k + "dynamic_friction_n", "> 0");
  expectRefused(sceneWithCutting({{"friction_n_per_m", -5.0}}).dump(), k + "friction_n_per_m", ">= 0");
  // F_d above (and equal to) F_s: no hysteresis.
  expectRefused(sceneWithCutting({{"static_friction_n", 0.6}, {"dynamic_friction_n", 0.8}}).dump(),
                k + "dynamic_friction_n", "below static friction F_s = 0.6 N");
  expectRefused(sceneWithCutting({{"static_friction_n", 0.6}, {"dynamic_friction_n", 0.6}}).dump(),
                k + "dynamic_friction_n", "below static friction");
  // Unknown key (typo) and a wrong type.
  expectRefused(sceneWithCutting({{"static_friction", 0.6}}).dump(), k + "static_friction", "did you mean");
  expectRefused(sceneWithCutting({{"press_threshold_n", "1"}}).dump(), k + "press_threshold_n", "expected a number");
}

}  // namespace
}  // namespace inc
