// The viewer's live plots: what the Timing, Haptics and Energy panels plot, fed from simulation snapshots.
#include <gtest/gtest.h>

#include "viewer/live_plots.h"

namespace inc::viewer {
namespace {

SimSnapshot snapshot(double step_ms, std::size_t particles, bool haptics) {
  SimSnapshot s;
  s.advance_ms = step_ms;
  s.particles = particles;
  s.report.stages = {{"predict", 0.5 * step_ms}, {"constraints", 0.25 * step_ms}};
  s.report.kinetic_energy = 1.0;
  s.report.elastic_energy = 2.0;
  s.report.potential_energy = -0.5;
  s.report.counters["broken_bonds"] = double(particles) / 10;
  if (haptics) {
    s.report.counters[kHapticRateCounter] = 998.0;
    s.report.counters[kHapticP99Counter] = 1.25;
  }
  return s;
}

// Per-stage frame time, step time, energies (and their sum), particle count and counters each get a history
// with the snapshot's values, newest last; haptic counters go to the Haptics plots, not the generic ones.
TEST(ViewerLivePlots, SnapshotsFeedStageEnergyParticleAndHapticPlots) {
  LivePlots p;
  p.push(snapshot(4.0, 100, true));
  p.push(snapshot(8.0, 120, true));
  p.pushFrameRate(60.0);
  ASSERT_NE(p.stage("predict"), nullptr);
  ASSERT_NE(p.stage("constraints"), nullptr);
  EXPECT_EQ(p.stage("integrate"), nullptr);
  EXPECT_FLOAT_EQ(p.stage("predict")->last(), 4.0f);
  EXPECT_FLOAT_EQ(p.stage("predict")->recent(1), 2.0f);
  EXPECT_FLOAT_EQ(p.stage("constraints")->last(), 2.0f);
  EXPECT_FLOAT_EQ(p.step().last(), 8.0f);
  EXPECT_FLOAT_EQ(p.fps().last(), 60.0f);
  EXPECT_FLOAT_EQ(p.total().last(), 2.5f);  // kinetic + elastic + potential
  EXPECT_FLOAT_EQ(p.particles().last(), 120.0f);
  EXPECT_FLOAT_EQ(p.particles().recent(1), 100.0f);
  EXPECT_EQ(p.particles().count(), 2u);
  ASSERT_TRUE(p.hasHaptics());
  EXPECT_FLOAT_EQ(p.hapticRate().last(), 998.0f);
  EXPECT_FLOAT_EQ(p.hapticP99().last(), 1.25f);
  EXPECT_EQ(p.counter(kHapticRateCounter), nullptr);
  ASSERT_NE(p.counter("broken_bonds"), nullptr);
  EXPECT_FLOAT_EQ(p.counter("broken_bonds")->last(), 12.0f);

  LivePlots none;
  none.push(snapshot(1.0, 10, false));
  EXPECT_FALSE(none.hasHaptics());
}

// The ring keeps the newest `length` samples in order.
TEST(ViewerLivePlots, HistoryRingKeepsTheNewestSamples) {
  History h(5);
  for (int i = 1; i <= 12; ++i) h.push(i);
  EXPECT_EQ(h.count(), 12u);
  for (std::size_t k = 0; k < 5; ++k) EXPECT_FLOAT_EQ(h.recent(k), float(12 - k));
}

}  // namespace
}  // namespace inc::viewer
