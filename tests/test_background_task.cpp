// BackgroundTask (host/background_task.h): tasks run on another thread, one after another; wait() returns after the task and rethrows what it threw.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <thread>

#include "host/background_task.h"

namespace inc {
namespace {

TEST(BackgroundTask, RunsEachTaskOnItsWorkerAndRethrowsItsError) {
  BackgroundTask worker;
  const std::thread::id caller = std::this_thread::get_id();
  std::thread::id first, second;
  int sum = 0;
  worker.start([&] { first = std::this_thread::get_id(); sum += 1; });
  worker.wait();
  worker.start([&] { second = std::this_thread::get_id(); sum += 2; });
  worker.wait();
  EXPECT_EQ(sum, 3);             // both ran, and wait() saw their writes
  EXPECT_NE(first, caller);      // not on the caller's thread
  EXPECT_EQ(first, second);      // one long-lived worker
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

}  // namespace
}  // namespace inc
