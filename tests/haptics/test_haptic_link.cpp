// Tests of the haptic link: tick times to rate and p99 (the model counters), the data time for the stall fade.
#include <gtest/gtest.h>

#include "host/haptics/haptic_link.h"

namespace inc {
namespace {

// 100 periods of 1 ms and one of 5 ms: rate = periods / their sum, p99 = the ceil(0.99 n)-th smallest period
// (the same rule as computePeriodStats), so one late period in 101 is not the p99 and two are; p50 is the median,
// max the longest period of the window.
TEST(HapticLink, WindowRateAndP99FollowTheTickTimes) {
  HapticLink link;
  double t = 0.0;
  ForceResult r;
  link.stamp(r, t);
  for (int i = 0; i < 100; ++i) link.stamp(r, t += 1e-3);
  link.stamp(r, t += 5e-3);
  HapticWindow w = link.frameDone();
  EXPECT_EQ(w.ticks, 102u);
  EXPECT_EQ(w.periods, 101u);
  EXPECT_NEAR(w.rate_hz, 101.0 / 0.105, 1e-6);
  EXPECT_NEAR(w.p99_ms, 1.0, 1e-9);
  EXPECT_NEAR(w.p50_ms, 1.0, 1e-9);
  EXPECT_NEAR(w.max_ms, 5.0, 1e-9);
  link.stamp(r, t += 5e-3);  // a second late period: now 2 of 102 are above the 99th percentile's rank
  w = link.frameDone();
  EXPECT_EQ(w.periods, 102u);
  EXPECT_NEAR(w.p99_ms, 5.0, 1e-9);
  // The window keeps the newest 1000 periods only: 1000 more of 2 ms replace every earlier one.
  for (int i = 0; i < 1000; ++i) link.stamp(r, t += 2e-3);
  w = link.frameDone();
  EXPECT_EQ(w.periods, 1000u);
  EXPECT_NEAR(w.rate_hz, 500.0, 1e-6);
  EXPECT_NEAR(w.p99_ms, 2.0, 1e-9);
  EXPECT_NEAR(w.p50_ms, 2.0, 1e-9);
  EXPECT_NEAR(w.max_ms, 2.0, 1e-9);  // the 5 ms periods left the window
}

// The force is stamped with the newest tick time the simulation thread saw after its last frame; before any
// data time is set none is stamped (no stall fade), and a model's own older data time wins.
TEST(HapticLink, StampsTheSimulationsDataTime) {
  HapticLink link;
  ForceResult r;
  EXPECT_LT(link.stamp(r, 0.0).data_time_s, 0.0);
  link.setDataTime(0.0);
  EXPECT_EQ(link.stamp(r, 0.001).data_time_s, 0.0);
  link.stamp(r, 0.002);
  link.frameDone();  // newest tick seen: 0.002 s
  EXPECT_EQ(link.stamp(r, 0.003).data_time_s, 0.002);
  ForceResult own;
  own.data_time_s = 0.0005;
  EXPECT_EQ(link.stamp(own, 0.004).data_time_s, 0.0005);
}

// A simulation thread that stops draining fills the ring: the dropped ticks restart the period chain, so the gap
// never shows as one long period (and nothing blocks the haptic side).
TEST(HapticLink, FullRingDropsTicksWithoutAFalsePeriod) {
  HapticLink link;
  ForceResult r;
  double t = 0.0;
  for (int i = 0; i < 9000; ++i) link.stamp(r, t += 1e-3);  // more than the ring holds (8191)
  link.frameDone();
  t += 0.5;  // ticks lost in the gap
  for (int i = 0; i < 10; ++i) link.stamp(r, t += 1e-3);
  const HapticWindow w = link.frameDone();
  EXPECT_NEAR(w.p99_ms, 1.0, 1e-6);
  EXPECT_EQ(w.ticks, 8191u + 10u);
}

}  // namespace
}  // namespace inc
