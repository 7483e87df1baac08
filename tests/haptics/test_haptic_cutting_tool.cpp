// Tests of the cutting tool composition: press, drag to cut (event), friction on the hand, halt (event), lift.
#include <gtest/gtest.h>

#include "host/haptics/cutting_tool.h"

namespace inc {
namespace {

// Elastic half-space spring: normal stiffness 500 N/m, tangential 200 N/m (force on the hand).
ForceResult spring(const TipContact& c) {
  const Vec3d& d = c.displacement_m;
  ForceResult r;
  r.force_n = Vec3d{-200.0 * d.x, -200.0 * d.y, -500.0 * d.z};
  return r;
}

TEST(HapticCuttingTool, PressDragHaltDrivesEventsAndFriction) {
  CutThresholds<double> th;  // F_p 1 N, F_s 0.6 N, F_d 0.3 N, k = 200 N/m
  const Vec3d surface{0.0, 0.0, 0.0};
  CuttingTool tool(spring, th, surface, Vec3d{0, 0, 1});
  Trajectory tr;
  auto add = [&](double t, double x, double z) {
    DeviceSample s;
    s.t_s = t;
    s.position_m = {x, 0.0, z};
    tr.samples.push_back(s);
  };
  add(0.0, 0.0, 0.001);      // above
  add(0.1, 0.0, -0.003);     // pressed 3 mm: |f_n| = 1.5 N > F_p, the blade enters
  add(0.2, 0.004, -0.003);   // dragged: the elastic drag 200 x passes F_s = 0.6 N at x = 3 mm -> cut
  add(0.3, 0.008, -0.003);   // cutting on
  add(0.35, 0.008, -0.003);  // halted: no friction left, |f_t| = 0 < F_d -> stop, in the tissue
  add(0.45, 0.008, 0.001);   // lifted
  ScriptedDevice dev(tr, ScriptedDevice::Mode::kByTime, 10.0);
  FakeClock clock;
  HapticLoopConfig cfg;
  cfg.max_force_rate_n_per_s = 1e6;
  HapticLoop loop(
      dev, [&](const ForceRequest& q) { return tool.tick(q); }, cfg, &clock);
  loop.runTicks(260);
  EXPECT_EQ(tool.state(), CutState::kCutting);
  // Mid-drag (t = 0.25 s): the anchor follows the blade (no elastic drag), friction k * depth = 200 * 0.003
  // = 0.6 N against the +x motion; the normal reaction 500 N/m * 3 mm = 1.5 N pushes the blade out.
  const TickRecord& mid = loop.records()[250];
  EXPECT_NEAR(mid.model_force_n.x, -0.6, 1e-9);
  EXPECT_NEAR(mid.model_force_n.z, 1.5, 1e-9);
  EXPECT_EQ(tool.anchor().x, loop.records().back().sample.position_m.x);  // the anchor is under the blade
  loop.runTicks(45);  // to t = 0.304: halted in the tissue at t = 0.3
  EXPECT_EQ(tool.state(), CutState::kStopped);
  EXPECT_NEAR(loop.records().back().model_force_n.x, 0.0, 1e-12);  // halted: no friction, no drag yet
  loop.runTicks(155);
  EXPECT_EQ(tool.state(), CutState::kIdle);
  EXPECT_EQ(norm(loop.records().back().model_force_n), 0.0);  // out of the tissue: no force
  CutEvent e;
  ASSERT_TRUE(tool.events().pop(e));
  EXPECT_TRUE(e.start);
  EXPECT_NEAR(e.position_m.x, 0.003, 1e-4);  // the drag passes 0.6 N at x = 3 mm
  ASSERT_TRUE(tool.events().pop(e));
  EXPECT_FALSE(e.start);
  EXPECT_NEAR(e.position_m.x, 0.008, 1e-12);  // stopped where the blade halted
  EXPECT_NEAR(e.t_s, 0.301, 1.5e-3);
  EXPECT_FALSE(tool.events().pop(e));
  EXPECT_EQ(tool.droppedEvents(), 0u);
}

TEST(HapticCuttingTool, ShallowBladeStopsWhenFrictionFallsBelowDynamicThreshold) {
  CutThresholds<double> th;  // k = 200 N/m: friction k * depth < F_d = 0.3 N once depth < 1.5 mm
  CuttingTool tool(spring, th, Vec3d{}, Vec3d{0, 0, 1});
  Trajectory tr;
  auto add = [&](double t, double x, double z) {
    DeviceSample s;
    s.t_s = t;
    s.position_m = {x, 0.0, z};
    tr.samples.push_back(s);
  };
  add(0.0, 0.0, -0.003);
  add(0.1, 0.005, -0.003);    // cut starts at x = 3 mm
  add(0.26, 0.021, -0.0014);  // rising while cutting: depth passes 1.5 mm at t = 0.25, x = 20 mm; then held
                              // (the drag from the new anchor, 200 N/m x 1 mm, stays below F_s)
  ScriptedDevice dev(tr, ScriptedDevice::Mode::kByTime, 10.0);
  FakeClock clock;
  HapticLoop loop(
      dev, [&](const ForceRequest& q) { return tool.tick(q); }, HapticLoopConfig{}, &clock);
  loop.runTicks(300);
  CutEvent e;
  ASSERT_TRUE(tool.events().pop(e));
  EXPECT_TRUE(e.start);
  ASSERT_TRUE(tool.events().pop(e));
  EXPECT_FALSE(e.start);
  EXPECT_NEAR(e.t_s, 0.25, 2e-3);
  EXPECT_NEAR(-e.position_m.z, 1.5e-3, 2e-5);
  EXPECT_FALSE(tool.events().pop(e));
  EXPECT_EQ(tool.state(), CutState::kStopped);
}

}  // namespace
}  // namespace inc
