// Tests of the cutting tool composition: press, drag to cut (event), friction on the hand, release (event).
#include <gtest/gtest.h>

#include "host/haptics/cutting_tool.h"

namespace inc {
namespace {

TEST(HapticCuttingTool, PressDragReleaseDrivesEventsAndFriction) {
  // Elastic half-space spring: normal stiffness 500 N/m, tangential 200 N/m (force on the hand).
  auto elastic = [](const Vec3d& d) {
    ForceResult r;
    if (d.z < 0.0) r.force_n = Vec3d{-200.0 * d.x, -200.0 * d.y, -500.0 * d.z};
    return r;
  };
  CutThresholds<double> th;  // F_p 1 N, F_s 0.6 N, F_d 0.3 N, k = 200 N/m
  CuttingTool tool(elastic, th, Vec3d{}, Vec3d{0, 0, 1});
  Trajectory tr;
  auto add = [&](double t, double x, double z) {
    DeviceSample s;
    s.t_s = t;
    s.position_m = {x, 0.0, z};
    tr.samples.push_back(s);
  };
  add(0.0, 0.0, 0.001);    // above
  add(0.1, 0.0, -0.003);   // pressed 3 mm: |f_n| = 1.5 N > F_p
  add(0.2, 0.004, -0.003); // dragged 4 mm: |f_t| = 0.8 N > F_s -> cut
  add(0.3, 0.008, -0.003); // still dragging
  add(0.4, 0.008, 0.001);  // lifted: stop
  ScriptedDevice dev(tr, ScriptedDevice::Mode::kByTime, 10.0);
  FakeClock clock;
  HapticLoopConfig cfg;
  cfg.max_force_rate_n_per_s = 1e6;
  HapticLoop loop(dev, [&](const ForceRequest& q) { return tool.tick(q); }, cfg, &clock);
  loop.runTicks(260);
  EXPECT_EQ(tool.state(), CutState::kCutting);
  // Mid-drag (t = 0.25 s): friction k * depth = 200 * 0.003 = 0.6 N against +x motion.
  const TickRecord& mid = loop.records()[250];
  EXPECT_NEAR(mid.model_force_n.x, -200.0 * mid.sample.position_m.x - 0.6, 1e-9);
  loop.runTicks(200);
  EXPECT_EQ(tool.state(), CutState::kIdle);
  CutEvent e;
  ASSERT_TRUE(tool.events().pop(e));
  EXPECT_TRUE(e.start);
  EXPECT_NEAR(e.position_m.x, 0.003, 1e-4);  // |f_t| passes 0.6 N at x = 3 mm
  ASSERT_TRUE(tool.events().pop(e));
  EXPECT_FALSE(e.start);
  EXPECT_FALSE(tool.events().pop(e));
  EXPECT_EQ(tool.droppedEvents(), 0u);
}

}  // namespace
}  // namespace inc
