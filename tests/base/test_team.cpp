// The CPU team of threads (base/team.h): multi-phase steps give the serial result, a stalled barrier
// hands the rest of the step to the lead thread, and the runner backs off to one thread after a stall.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

#include "base/team.h"

using namespace inc;

namespace {

// `phases` rounds of a three-point smoothing (read x, write y; barrier; copy back; barrier): every round reads
// neighbours another thread wrote, so a missing or misplaced barrier changes the result. `stall_phase`: thread 1
// sleeps `stall_ms` at the start of that round (a descheduled team member).
std::vector<double> smooth(cpu::TeamRunner& runner, int threads, int phases, int stall_phase = -1, int stall_ms = 0) {
  const std::int64_t n = 1000;
  std::vector<double> x(n), y(n);
  for (std::int64_t i = 0; i < n; ++i) x[i] = double((i * 7919) % 101);
  runner.run(threads, [&](const cpu::Team& t) {
    for (int ph = 0; ph < phases; ++ph) {
      if (ph == stall_phase && t.id() == 1) std::this_thread::sleep_for(std::chrono::milliseconds(stall_ms));
      for (std::int64_t i = t.begin(n), e = t.end(n); i < e; ++i)
        y[i] = 0.25 * x[i > 0 ? i - 1 : i] + 0.5 * x[i] + 0.25 * x[i + 1 < n ? i + 1 : i];
      t.barrier();
      for (std::int64_t i = t.begin(n), e = t.end(n); i < e; ++i) x[i] = y[i];
      t.barrier();
    }
  });
  return x;
}

}  // namespace

TEST(CpuTeam, MultiPhaseStepEqualsSerial) {
  cpu::TeamRunner serial, team;
  const std::vector<double> ref = smooth(serial, 1, 50);
  EXPECT_EQ(serial.lastThreads(), 1);
  const std::vector<double> got = smooth(team, 2, 50);
  EXPECT_EQ(team.lastThreads(), 2);
  ASSERT_EQ(got.size(), ref.size());
  for (std::size_t i = 0; i < ref.size(); ++i) ASSERT_EQ(got[i], ref[i]) << "item " << i;  // bit for bit
}

TEST(CpuTeam, StalledBarrierHandsTheStepToTheLead) {
  cpu::TeamRunner serial, team;
  const std::vector<double> ref = smooth(serial, 1, 20);
  // Thread 1 sleeps 250 ms in round 5 while thread 0 waits at the barrier (stall limit: 10 ms, or twice the
  // waiter's own work): the team stalls, thread 0 finishes the step alone, and the result is unchanged.
  const std::vector<double> got = smooth(team, 2, 20, 5, 250);
  EXPECT_TRUE(team.lastStalled());
  EXPECT_EQ(team.stalledSteps(), 1);
  for (std::size_t i = 0; i < ref.size(); ++i) ASSERT_EQ(got[i], ref[i]) << "item " << i;
  // Back-off: the next 8 steps run on one thread, then the team is tried again.
  for (int k = 0; k < 8; ++k) {
    const std::vector<double> again = smooth(team, 2, 3);
    EXPECT_EQ(team.lastThreads(), 1) << "step " << k << " after the stall";
  }
  smooth(team, 2, 3);
  EXPECT_EQ(team.lastThreads(), 2);
}
