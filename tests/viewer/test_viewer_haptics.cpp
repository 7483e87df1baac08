// The viewer with a haptics scene: the mouse drives the PointerDevice of the model's haptic loop (xvfb-run -a).
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "host/haptics/haptic_scene_model.h"
#include "host/haptics/pointer_device.h"
#include "host/scene/scene_compile.h"
#include "tests/support/viewer_test_model.h"
#include "viewer/gl_window.h"
#include "viewer/viewer_app.h"

namespace inc::viewer {
namespace {

bool displayAvailable(std::string& why) {
  GlWindowOptions o;
  o.width = o.height = 32;
  o.visible = false;
  return GlWindow::open(o, &why) != nullptr;
}

// A ball with its haptic loop on a PointerDevice; the cursor over it with the tip pressed 4 mm in. Each frame the
// viewer sends the tip as the device pose, shifted along the tissue plane's normal so that its depth below the
// plane is the press depth's component along the normal (to 1e-9 m), tangentially where the tip is; the loop's
// local model then pushes the hand out of the tissue with the tip stiffness times that depth (within 5 %: the ball
// sags a little under the cursor while the anchor stays where the tip entered).
TEST(ViewerHaptics, MouseDrivesThePointerDeviceIntoTheTissuePlane) {
  std::string why;
  if (!displayAvailable(why)) GTEST_SKIP() << "no display (run under xvfb-run -a): " << why;
  Scene scene;
  scene.file = "<test:viewer_haptics>";
  scene.models.mls = true;
  scene.models.haptics = true;
  auto pointer = std::make_shared<PointerDevice>(3.3);
  SceneHapticsOptions ho;
  ho.device = pointer;
  ho.record_s = 10.0;
  auto model = std::make_unique<HapticSceneModel>(std::make_unique<testing::SaggingBall>(), compileScene(scene), ho);
  HapticSceneModel* haptic = model.get();
  const TissuePlane plane = haptic->haptics().plane();
  const double press = 0.004;
  ViewerOptions o;
  o.model = std::move(model);
  o.width = 320;
  o.height = 240;
  o.frames = 6;
  o.show_ui = false;
  o.cursor_x = 0.5;
  o.cursor_y = 0.5;
  o.press_depth_m = press;
  o.haptic_pointer = pointer;
  o.haptic_plane_point_m = plane.point_m;
  o.haptic_plane_normal = plane.normal;
  ViewerFrameInfo last;
  o.on_frame = [&last](const ViewerFrameInfo& f) { last = f; };
  ASSERT_EQ(runViewer(o), 0);
  ASSERT_TRUE(last.tool_on_surface);
  haptic->haptics().stop();  // the test thread is now the device's only reader
  const DeviceSample pose = pointer->read(0, 0.0);
  const Vec3d& n = plane.normal;
  const Vec3d dir = (last.tool_tip - last.camera.eye) * (1.0 / norm(last.tool_tip - last.camera.eye));
  const double depth = dot(plane.point_m - pose.position_m, n);
  EXPECT_NEAR(depth, -press * dot(dir, n), 1e-9);
  ASSERT_GT(depth, 0.0);  // the default camera looks down on the plane
  const Vec3d off = pose.position_m - last.tool_tip;
  EXPECT_NEAR(norm(off - n * dot(off, n)), 0.0, 1e-12);
  ASSERT_FALSE(haptic->haptics().loop().records().empty());
  const Vec3d f = haptic->haptics().loop().records().back().model_force_n;
  const TipStiffness& k = haptic->haptics().tipStiffness();
  const double k_nn = dot(n, k.handForce(n * -1.0));
  EXPECT_NEAR(dot(f, n), k_nn * depth, 0.05 * k_nn * depth);
}

}  // namespace
}  // namespace inc::viewer
