// Tests of the mouse/keyboard device: UI-thread poses reach the haptic loop, forces come back for display.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "host/haptics/haptic_loop.h"
#include "host/haptics/pointer_device.h"

namespace inc {
namespace {

TEST(HapticPointer, PosesInForcesOutAcrossThreads) {
  PointerDevice dev(2.0);
  HapticLoop loop(dev, [](const ForceRequest& q) { return ForceResult{q.sample.position_m * -100.0, -1.0}; });
  loop.start();
  const double q[4] = {2.0, 0.0, 0.0, 0.0};  // normalised on the way in
  for (int i = 1; i <= 50; ++i) {
    dev.setPose(Vec3d{0.001 * i, 0.0, 0.0}, q, 1);
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  loop.stop();
  const TickRecord& last = loop.records().back();
  EXPECT_EQ(last.sample.position_m.x, 0.05);
  EXPECT_EQ(last.sample.orientation[0], 1.0);
  EXPECT_EQ(last.sample.buttons, 1u);
  // -100 N/m * 0.05 m = -5 N, clamped to the device's 2 N.
  EXPECT_NEAR(dev.displayForce().x, -2.0, 1e-12);
}

}  // namespace
}  // namespace inc
