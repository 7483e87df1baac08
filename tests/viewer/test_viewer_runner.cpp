// The viewer's simulation runner: knobs reach the model, pause/step/reset, the failure guard, the worker thread.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "tests/support/viewer_test_model.h"
#include "viewer/sim_runner.h"

namespace inc::viewer {
namespace {

using testing::SaggingBall;

std::vector<ViewerKnob> youngsKnob() {
  ViewerKnob k;
  k.label = "Young's modulus [Pa]";
  k.min_value = 1e3;
  k.max_value = 1e6;
  k.value = 1e4;
  k.logarithmic = true;
  k.apply = [](SimulationModel& m, double e) { dynamic_cast<SaggingBall&>(m).setYoungsModulus(e); };
  return {k};
}

// Deflection at equilibrium is q L^2 / E (L = 0.2 m diameter, q = 50): the slider's value must reach the model.
TEST(ViewerRunner, YoungsModulusKnobChangesDeflection) {
  SimRunner run(std::make_unique<SaggingBall>(), nullptr, youngsKnob(), 1.0 / 60, /*threaded=*/false);
  SimSnapshot s;
  std::uint64_t ver = 0;
  for (int i = 0; i < 60; ++i) run.pump();  // 1 s = 50 tau: relaxed to 1e-21
  ASSERT_TRUE(run.latest(s, ver));
  const double L = 0.2;
  // The icosphere's leftmost vertex is at x = -R exactly and the rightmost at +R: the max is q L^2 / E.
  EXPECT_NEAR(s.report.max_displacement, 50.0 * L * L / 1e4, 1e-9);
  run.setKnob(0, 4e4);
  for (int i = 0; i < 60; ++i) run.pump();
  ASSERT_TRUE(run.latest(s, ver));
  EXPECT_NEAR(s.report.max_displacement, 50.0 * L * L / 4e4, 1e-9);
  EXPECT_DOUBLE_EQ(s.report.counters.at("youngs_pa"), 4e4);
  // Out of range: clamped to the knob's bounds.
  run.setKnob(0, 1e9);
  EXPECT_DOUBLE_EQ(run.knobs()[0].value, 1e6);
}

// Snapshots carry the model's RenderLayers only while the viewer wants them; asking while paused republishes
// the current state with them at once (no frame advanced).
TEST(ViewerRunner, RenderLayersOnlyWhenWantedAndRepublishedWhilePaused) {
  class WithLayers : public SaggingBall {
   public:
    void renderLayers(RenderLayers& out) const override {
      ++calls;
      out = RenderLayers{};
      out.sphere_centres = {{0, 0, 0}, {0.1, 0, 0}};
      out.sphere_radii = {0.05, 0.02};
    }
    mutable int calls = 0;
  };
  auto model = std::make_unique<WithLayers>();
  WithLayers* raw = model.get();
  SimRunner run(std::move(model), nullptr, {}, 1.0 / 60, false);
  SimSnapshot s;
  std::uint64_t ver = 0;
  run.pump();
  ASSERT_TRUE(run.latest(s, ver));
  EXPECT_TRUE(s.layers.sphere_centres.empty());
  EXPECT_EQ(raw->calls, 0);
  run.setPaused(true);
  run.setLayersWanted(true);
  run.pump();  // paused: no frame, but the state is published again with its layers
  ASSERT_TRUE(run.latest(s, ver));
  EXPECT_EQ(s.frame, 1u);
  ASSERT_EQ(s.layers.sphere_radii.size(), 2u);
  EXPECT_DOUBLE_EQ(s.layers.sphere_radii[1], 0.02);
  EXPECT_EQ(raw->calls, 1);
  run.pump();
  EXPECT_FALSE(run.latest(s, ver));  // nothing new while paused
  run.setLayersWanted(false);
  run.setPaused(false);
  run.pump();
  ASSERT_TRUE(run.latest(s, ver));
  EXPECT_TRUE(s.layers.sphere_centres.empty());
  EXPECT_EQ(raw->calls, 1);
}

TEST(ViewerRunner, PauseStepResetAndStepSafety) {
  int built = 0;
  auto factory = [&built] {
    ++built;
    return std::unique_ptr<SimulationModel>(std::make_unique<SaggingBall>());
  };
  SimRunner run(nullptr, factory, {}, 0.01, false);
  EXPECT_EQ(built, 1);
  SimSnapshot s;
  std::uint64_t ver = 0;
  run.pump();
  run.pump();
  run.latest(s, ver);
  EXPECT_EQ(s.frame, 2u);
  EXPECT_NEAR(s.sim_time_s, 0.02, 1e-15);
  run.setPaused(true);
  run.pump();
  EXPECT_FALSE(run.latest(s, ver));  // paused: nothing new
  run.stepOnce();
  run.pump();
  run.pump();
  ASSERT_TRUE(run.latest(s, ver));
  EXPECT_EQ(s.frame, 3u);  // exactly one more
  // Slow motion: a quarter of the simulated time per frame.
  run.setTimeScale(0.25);
  run.stepOnce();
  run.pump();
  run.latest(s, ver);
  EXPECT_NEAR(s.sim_time_s, 0.0325, 1e-15);
  EXPECT_NEAR(s.report.dt, 0.0025, 1e-15);
  // Step safety 0.5 is forwarded as scaleTimeStep(0.5): the model's dt halves.
  run.setStepSafety(0.5);
  run.stepOnce();
  run.pump();
  run.latest(s, ver);
  EXPECT_NEAR(s.report.dt, 0.00125, 1e-15);
  run.reset();
  run.pump();  // paused: applies the reset, advances nothing
  run.latest(s, ver);
  EXPECT_EQ(built, 2);
  EXPECT_EQ(s.frame, 0u);
  EXPECT_DOUBLE_EQ(s.report.max_displacement, 0.0);
  // After a reset the step safety is re-applied to the new model.
  run.stepOnce();
  run.pump();
  run.latest(s, ver);
  EXPECT_NEAR(s.report.dt, 0.0025 * 0.5, 1e-15);
}

TEST(ViewerRunner, NonFiniteFrameRollsBackAndPauses) {
  auto ball = std::make_unique<SaggingBall>();
  SaggingBall* raw = ball.get();
  SimRunner run(std::move(ball), nullptr, {}, 0.01, false);
  raw->poisonNextFrame();
  run.pump();
  SimSnapshot s;
  std::uint64_t ver = 0;
  run.latest(s, ver);
  EXPECT_TRUE(s.failed);
  EXPECT_NE(s.failure.find("integrate"), std::string::npos);
  EXPECT_TRUE(run.paused());
  std::vector<Vec3d> p;
  raw->currentPositions(p);
  for (const auto& v : p) ASSERT_TRUE(std::isfinite(v.y));  // rolled back to the checkpoint
}

// Threaded: the model advances without anyone pumping, in real time, and a reader never blocks on a step.
TEST(ViewerRunner, WorkerThreadAdvancesOnItsOwn) {
  SimRunner run(std::make_unique<SaggingBall>(), nullptr, youngsKnob(), 0.005, true);
  ASSERT_TRUE(run.waitForFrame(10, 5.0));
  run.setKnob(0, 2e4);
  run.setPaused(true);
  SimSnapshot s;
  std::uint64_t ver = 0;
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  run.latest(s, ver);
  const std::uint64_t frozen = s.frame;
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  run.latest(s, ver);
  EXPECT_EQ(s.frame, frozen);  // paused stays paused
  run.setPaused(false);
  ASSERT_TRUE(run.waitForFrame(frozen + 5, 5.0));
  run.latest(s, ver);
  EXPECT_DOUBLE_EQ(s.report.counters.at("youngs_pa"), 2e4);
}

}  // namespace
}  // namespace inc::viewer
