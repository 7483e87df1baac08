// Tests of the haptic loop: fake-clock bookkeeping, safety chain, triple buffer, record -> replay.
#include <gtest/gtest.h>

#include <linux/capability.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cstdio>
#include <thread>

#include "host/haptics/haptic_loop.h"
#include "model/input_error.h"
#include "physics/haptic_safety.h"
#include "test_paths.h"

namespace inc {
namespace {

Trajectory linePath(double duration_s, int n) {
  Trajectory tr;
  for (int i = 0; i <= n; ++i) {
    DeviceSample s;
    s.t_s = duration_s * i / n;
    s.position_m = {0.01 * i / n, 0.0, -0.002 * i / n};
    s.buttons = i % 2;
    tr.samples.push_back(s);
  }
  return tr;
}

TEST(HapticLoop, FakeClockPeriodsAndMissedDeadlines) {
  FakeClock clock;
  ScriptedDevice dev(linePath(1.0, 10), ScriptedDevice::Mode::kByTime);
  // Every 10th tick "computes" for 1.5 ms: that tick overruns, the next period is 1.5 ms (missed),
  // and the schedule then catches up on the following deadline.
  ForceModel model = [&](const ForceRequest& r) {
    clock.advance(r.tick % 10 == 5 ? 1.5e-3 : 1.0e-4);
    return ForceResult{{0.1, 0.0, 0.0}, -1.0};
  };
  HapticLoopConfig cfg;
  HapticLoop loop(dev, model, cfg, &clock);
  loop.runTicks(100);
  const PeriodStats s = loop.stats();
  ASSERT_EQ(s.ticks, 100u);
  EXPECT_EQ(s.overruns, 10u);
  EXPECT_EQ(s.missed, 10u);  // ticks 6, 16, ..., 96 start 1.5 ms after their predecessor
  EXPECT_NEAR(s.p50_s, 1.0e-3, 1e-12);
  EXPECT_NEAR(s.max_s, 1.5e-3, 1e-12);
  EXPECT_NEAR(s.compute_max_s, 1.5e-3, 1e-12);
  // Schedule is kept: tick 7 is back on its slot (period 0.5 ms after the late tick 6).
  EXPECT_NEAR(loop.records()[7].t_s, 7.0e-3, 1e-12);
  EXPECT_NEAR(loop.records()[7].period_s, 0.5e-3, 1e-12);
  EXPECT_EQ(dev.forcesWritten(), 100u);
}

TEST(HapticLoop, FallingBehindSkipsDeadlinesInsteadOfBursting) {
  FakeClock clock;
  ScriptedDevice dev(linePath(1.0, 10), ScriptedDevice::Mode::kByTime);
  ForceModel model = [&](const ForceRequest& r) {
    clock.advance(r.tick == 3 ? 4.2e-3 : 0.0);
    return ForceResult{};
  };
  HapticLoop loop(dev, model, {}, &clock);
  loop.runTicks(6);
  const PeriodStats s = loop.stats();
  EXPECT_EQ(s.skipped, 3u);  // tick 3 ends at 7.2 ms: deadlines 4, 5, 6 ms are dropped, next is 7 ms
  EXPECT_NEAR(loop.records()[4].t_s, 7.2e-3, 1e-12);
  EXPECT_NEAR(loop.records()[5].t_s, 8.0e-3, 1e-12);
}

TEST(HapticLoop, SafetyClampRateLimitAndStallFade) {
  FakeClock clock;
  ScriptedDevice dev(linePath(1.0, 10), ScriptedDevice::Mode::kByTime, /*max_force_n=*/2.0);
  double data_time = 0.0;
  ForceModel model = [&](const ForceRequest&) { return ForceResult{{3.0, 0.0, 0.0}, data_time}; };
  HapticLoopConfig cfg;
  cfg.max_force_rate_n_per_s = 500.0;  // 0.5 N per 1 ms tick
  cfg.stall_after_s = 0.02;
  cfg.stall_fade_s = 0.01;
  HapticLoop loop(dev, model, cfg, &clock);
  loop.runTicks(10);
  const auto& rec = loop.records();
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(rec[i].force_n.x, 0.5 * (i + 1), 1e-12) << i;  // ramp
  for (int i = 4; i < 10; ++i) EXPECT_NEAR(rec[i].force_n.x, 2.0, 1e-12) << i;           // clamped to device max
  // The simulation stalled at t = 0: at t = 25 ms the gain is 1 - (25 - 20) / 10 = 0.5 -> 1.5 N; it
  // leaves the 2 N clamp at 24 ms (gain 0.6 -> 1.8 N) and falls 0.3 N per tick, within the rate limit.
  loop.runTicks(16);  // ticks 10..25
  EXPECT_NEAR(rec[25].t_s, 0.025, 1e-12);
  EXPECT_NEAR(rec[23].force_n.x, 2.0, 1e-12);
  EXPECT_NEAR(rec[24].force_n.x, 1.8, 1e-12);
  EXPECT_NEAR(rec[25].force_n.x, 1.5, 1e-12);
  loop.runTicks(10);  // t >= 30 ms: fully faded
  EXPECT_NEAR(rec.back().force_n.x, 0.0, 1e-12);
  // Non-finite model output never reaches the device.
  EXPECT_EQ(norm(clampForce(Vec3d{NAN, 0.0, 0.0}, 1.0)), 0.0);
}

TEST(HapticLoop, BadConfigIsInputError) {
  ScriptedDevice dev(linePath(1.0, 2), ScriptedDevice::Mode::kByTime);
  HapticLoopConfig cfg;
  cfg.rate_hz = -5;
  EXPECT_THROW(HapticLoop(
                   dev, [](const ForceRequest&) { return ForceResult{}; }, cfg),
               InputError);
  Trajectory bad = linePath(1.0, 3);
  bad.samples[2].t_s = bad.samples[1].t_s;
  EXPECT_THROW(ScriptedDevice(bad, ScriptedDevice::Mode::kByTime), InputError);
}

TEST(HapticLoop, TripleBufferDeliversNewestCompleteValue) {
  struct Big {
    std::uint64_t a[16];
  };
  TripleBuffer<Big> tb;
  std::atomic<bool> done{false};
  std::uint64_t torn = 0, last = 0, regress = 0;
  std::thread reader([&] {
    while (!done.load()) {
      if (!tb.update()) continue;
      const Big& b = tb.front();
      for (int k = 1; k < 16; ++k) torn += b.a[k] != b.a[0];
      regress += b.a[0] < last;
      last = b.a[0];
    }
  });
  for (std::uint64_t v = 1; v <= 200000; ++v) {
    Big& b = tb.back();
    for (auto& x : b.a) x = v;
    tb.publish();
  }
  done = true;
  reader.join();
  tb.update();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(regress, 0u);
  EXPECT_EQ(tb.front().a[0], 200000u);  // the last value is never lost
  EXPECT_EQ(tb.publishes(), 200000u);
}

TEST(HapticLoop, RecordThenReplayIsBitExact) {
  // Record on the real clock (jittery times), replay by tick on a fake clock: same forces bit for bit.
  ScriptedDevice dev(linePath(0.05, 7), ScriptedDevice::Mode::kByTime);
  auto model = [](const ForceRequest& r) {
    const Vec3d p = r.sample.position_m;
    return ForceResult{{-300.0 * p.x + 0.1 * std::sin(p.z * 1e3), 200.0 * p.z * p.x, double(r.sample.buttons)}, -1.0};
  };
  HapticLoop rec_loop(dev, model);
  rec_loop.runTicks(60);
  const std::string path = std::string(INCISION_BINARY_DIR) + "/haptic_replay_test.traj";
  writeTrajectory(path, rec_loop.recordedTrajectory());
  ScriptedDevice replay(loadTrajectory(path), ScriptedDevice::Mode::kByTick);
  FakeClock clock;
  HapticLoop rep_loop(replay, model, {}, &clock);
  rep_loop.runTicks(60);
  for (std::size_t i = 0; i < 60; ++i) {
    const Vec3d a = rec_loop.records()[i].force_n, b = rep_loop.records()[i].force_n;
    EXPECT_TRUE(a.x == b.x && a.y == b.y && a.z == b.z) << "tick " << i;
  }
  std::remove(path.c_str());
}

TEST(HapticLoop, RealThreadRunsAndStops) {
  ScriptedDevice dev(linePath(1.0, 10), ScriptedDevice::Mode::kByTime);
  HapticLoop loop(dev, [](const ForceRequest&) { return ForceResult{}; });
  loop.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  loop.status().update();
  const std::uint64_t seen = loop.status().front().tick;
  loop.stop();
  EXPECT_GT(loop.records().size(), 20u);  // ~50 ticks at 1 kHz; loose: the CI machine is shared
  EXPECT_LE(seen, loop.records().size());
}

// The thread reports how it is scheduled: SCHED_FIFO where the process may (the message says so), else the
// normal policy with a message naming what was refused; off when not asked. Either way the loop runs.
TEST(HapticLoop, ThreadReportsItsScheduling) {
  ScriptedDevice dev(linePath(1.0, 10), ScriptedDevice::Mode::kByTime);
  {
    HapticLoop loop(dev, [](const ForceRequest&) { return ForceResult{}; });
    loop.start();
    const HapticScheduling s = loop.scheduling();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    loop.stop();
    std::printf("haptic thread: %s\n", s.message.c_str());
    if (s.realtime) {
      EXPECT_EQ(s.priority, HapticLoopConfig{}.realtime_priority);
      EXPECT_EQ(s.spin_margin_s, HapticLoopConfig{}.realtime_spin_margin_s);
      EXPECT_EQ(s.message.rfind("SCHED_FIFO priority", 0), 0u);
    } else {
      EXPECT_EQ(s.priority, 0);
      EXPECT_EQ(s.spin_margin_s, HapticLoopConfig{}.spin_margin_s);
      EXPECT_NE(s.message.find("SCHED_FIFO refused"), std::string::npos);
    }
    EXPECT_GT(loop.records().size(), 5u);
  }
  HapticLoopConfig cfg;
  cfg.realtime = false;
  HapticLoop loop(
      dev, [](const ForceRequest&) { return ForceResult{}; }, cfg);
  loop.start();
  const HapticScheduling s = loop.scheduling();
  loop.stop();
  EXPECT_FALSE(s.realtime);
  EXPECT_EQ(s.message, "normal scheduling (realtime off)");
  cfg.realtime = true;
  cfg.realtime_priority = 100;
  EXPECT_THROW(HapticLoop(
                   dev, [](const ForceRequest&) { return ForceResult{}; }, cfg),
               InputError);
}

// The fallback itself: a thread without CAP_SYS_NICE (capabilities are per thread and inherited by the
// threads it creates) and with an rtprio limit below the asked priority starts a loop that is refused
// SCHED_FIFO, says so, and still runs.
TEST(HapticLoop, RefusedRealtimeFallsBackWithAMessage) {
  rlimit rl{};
  ASSERT_EQ(getrlimit(RLIMIT_RTPRIO, &rl), 0);
  if (rl.rlim_cur >= rlim_t(HapticLoopConfig{}.realtime_priority))
    GTEST_SKIP() << "the rtprio limit allows SCHED_FIFO " << HapticLoopConfig{}.realtime_priority << " anyway";
  HapticScheduling s;
  std::size_t ticks = 0;
  std::thread unprivileged([&] {
    __user_cap_header_struct hdr{_LINUX_CAPABILITY_VERSION_3, 0};
    __user_cap_data_struct data[2]{};
    if (syscall(SYS_capget, &hdr, data) != 0) return;
    data[CAP_SYS_NICE / 32].effective &= ~(1u << (CAP_SYS_NICE % 32));
    if (syscall(SYS_capset, &hdr, data) != 0) return;
    ScriptedDevice dev(linePath(1.0, 10), ScriptedDevice::Mode::kByTime);
    HapticLoop loop(dev, [](const ForceRequest&) { return ForceResult{}; });
    loop.start();
    s = loop.scheduling();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    loop.stop();
    ticks = loop.records().size();
  });
  unprivileged.join();
  std::printf("without CAP_SYS_NICE: %s\n", s.message.c_str());
  EXPECT_FALSE(s.realtime);
  EXPECT_NE(s.message.find("SCHED_FIFO refused"), std::string::npos);
  EXPECT_NE(s.message.find("CAP_SYS_NICE"), std::string::npos);  // says what to grant
  EXPECT_EQ(s.spin_margin_s, HapticLoopConfig{}.spin_margin_s);
  EXPECT_GT(ticks, 5u);
}

}  // namespace
}  // namespace inc

namespace inc {
namespace {

TEST(HapticLoop, AuthoredTrajectoryFileInterpolatesAndBadLinesAreInputErrors) {
  const std::string path = std::string(INCISION_BINARY_DIR) + "/haptic_authored_test.traj";
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fprintf(f, "# authored path\n0.0 0 0 0 1 0 0 0 0\n\n0.5 0.01 0 -0.002 1 0 0 0 1  # press\n");
    std::fclose(f);
  }
  ScriptedDevice dev(loadTrajectory(path), ScriptedDevice::Mode::kByTime);
  const DeviceSample s = dev.read(0, 0.25);
  EXPECT_NEAR(s.position_m.x, 0.005, 1e-15);
  EXPECT_NEAR(s.position_m.z, -0.001, 1e-15);
  EXPECT_EQ(dev.read(0, 9.0).position_m.x, 0.01);  // held after the end
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    std::fprintf(f, "0.0 0 0 0 1 0 0 0 0\n0.5 0.01 zero 0 1 0 0 0 1\n");
    std::fclose(f);
  }
  try {
    loadTrajectory(path);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "line 2");
  }
  EXPECT_THROW(loadTrajectory(path + ".missing"), InputError);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace inc
