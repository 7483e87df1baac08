// BackgroundTask (base/background_task.h): tasks run on another thread, one after another; wait() returns after the
// task and rethrows what it threw.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

#include "base/background_task.h"

namespace inc {
namespace {

TEST(BackgroundTask, RunsEachTaskOnItsWorkerAndRethrowsItsError) {
  BackgroundTask worker;
  const std::thread::id caller = std::this_thread::get_id();
  std::thread::id first, second;
  int sum = 0;
  worker.start([&] {
    first = std::this_thread::get_id();
    sum += 1;
  });
  worker.wait();
  worker.start([&] {
    second = std::this_thread::get_id();
    sum += 2;
  });
  worker.wait();
  EXPECT_EQ(sum, 3);         // both ran, and wait() saw their writes
  EXPECT_NE(first, caller);  // not on the caller's thread
  EXPECT_EQ(first, second);  // one long-lived worker
  worker.start([] { throw std::runtime_error("from the worker"); });
  EXPECT_THROW(worker.wait(), std::runtime_error);
  worker.start([&] { sum += 4; });  // still usable after an error
  worker.wait();
  EXPECT_EQ(sum, 7);
  worker.wait();  // nothing pending: returns at once
}

TEST(BackgroundTask, OverlapsWithTheCaller) {
  BackgroundTask worker;
  std::atomic<bool> caller_done{false}, saw_caller{false};
  worker.start([&] {
    for (int i = 0; i < 2000000 && !caller_done; ++i) std::this_thread::yield();
    saw_caller = caller_done.load();
  });
  caller_done = true;  // the caller goes on while the task runs
  worker.wait();
  EXPECT_TRUE(saw_caller);
}

// waitFor gives up on a task still running (false, the task untouched) and reports one that is done (true), with
// its error rethrown as wait() does.
TEST(BackgroundTask, WaitForGivesUpOnARunningTask) {
  BackgroundTask worker;
  std::atomic<bool> release{false};
  worker.start([&] {
    while (!release.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  });
  EXPECT_FALSE(worker.waitFor(5.0));
  EXPECT_FALSE(worker.done());
  release = true;
  EXPECT_TRUE(worker.waitFor(60000.0));
  worker.start([] { throw std::runtime_error("from the worker"); });
  EXPECT_THROW(worker.waitFor(60000.0), std::runtime_error);
  EXPECT_TRUE(worker.waitFor(0.0));  // nothing pending
}

#if defined(__linux__) && defined(SCHED_IDLE)
// An idle-priority worker: every task starts at SCHED_IDLE; boost() lifts the running task to SCHED_OTHER (where the
// process may raise a priority; skipped where it may not) and the next task starts idle again.
TEST(BackgroundTask, IdleTasksStartIdleAndABoostLastsForTheRunningTask) {
  BackgroundTask worker(true);
  const auto policy = [] {
    int p = -1;
    sched_param param{};
    pthread_getschedparam(pthread_self(), &p, &param);
    return p;
  };
  std::atomic<int> phase{0};
  int at_start = -1, after_boost = -1, next_start = -1;
  worker.start([&] {
    at_start = policy();
    phase = 1;
    while (phase.load() != 2) std::this_thread::yield();
    after_boost = policy();
  });
  // Sleep, not spin: an idle-priority thread runs only where a core idles.
  while (phase.load() != 1) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_FALSE(worker.done());
  worker.boost();
  phase = 2;
  worker.wait();
  EXPECT_TRUE(worker.done());
  worker.start([&] { next_start = policy(); });
  worker.wait();
  EXPECT_EQ(at_start, SCHED_IDLE);
  EXPECT_EQ(next_start, SCHED_IDLE);
  if (after_boost == SCHED_IDLE) GTEST_SKIP() << "raising a thread's priority is not permitted here";
  EXPECT_EQ(after_boost, SCHED_OTHER);
}
#endif

}  // namespace
}  // namespace inc
