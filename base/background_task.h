// One long-lived worker thread that runs one task at a time beside the caller (the cut's MLS rebuild while the
// caller rebuilds PBD). Long-lived so that its OpenMP thread pool is made once, not per task.
#pragma once

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#endif

#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>

#include "base/elapsed_ms.h"

namespace inc {

class BackgroundTask {
 public:
  // idle_priority: each task starts at idle priority, running only when a core would otherwise idle (Linux
  // SCHED_IDLE; best effort, ignored where refused): work that may lag behind the frames (a stroke's end) must not
  // slow them down on few cores. Measured on two cores: nice 10 instead still made the frames beside it 2x slower
  // (CFS time slices stall their OpenMP barriers); idle priority left them as they were.
  explicit BackgroundTask(bool idle_priority = false) : idle_priority_(idle_priority) {}
  BackgroundTask(const BackgroundTask&) = delete;
  BackgroundTask& operator=(const BackgroundTask&) = delete;
  ~BackgroundTask() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

  // Starts `task` on the worker (the previous one must have been waited for).
  void start(std::function<void()> task) {
    if (!thread_.joinable()) thread_ = std::thread([this] { loop(); });
    {
      std::lock_guard<std::mutex> lock(mutex_);
      task_ = std::move(task);
      error_ = nullptr;
      done_ = false;
    }
    wake_.notify_all();
  }

  // Runs `task` on the worker and `here` on the calling thread at the same time, then waits for the task (also when
  // `here` throws: the task never outlives the state both share). Rethrows what either threw; returns the
  // milliseconds the caller waited after `here` returned.
  template <typename Here>
  double runBeside(std::function<void()> task, Here&& here) {
    start(std::move(task));
    try {
      here();
    } catch (...) {
      wait();
      throw;
    }
    const auto t0 = std::chrono::steady_clock::now();
    wait();
    return msSince(t0);
  }

  bool done() {
    std::lock_guard<std::mutex> lock(mutex_);
    return done_;
  }

  // Before waiting on an idle-priority task: back to normal priority for the rest of it, so that a machine busy
  // with other work (a compile kept a 60 ms stroke end waiting 6.4 s) does not starve it while the caller waits.
  // Best effort: raising a priority needs CAP_SYS_NICE or an RLIMIT_NICE of 20 on Linux; elsewhere, or refused,
  // nothing changes (and threads the task started, OpenMP's, stay idle). The next task starts idle again.
  void boost() {
#if defined(__linux__) && defined(SCHED_IDLE)
    if (!idle_priority_ || !thread_.joinable()) return;
    sched_param p{};
    p.sched_priority = 0;
    pthread_setschedparam(thread_.native_handle(), SCHED_OTHER, &p);
#endif
  }

  // Waits at most `ms` milliseconds for the task started last: true when it is done (then as wait(): rethrows what
  // it threw), false when it is still running.
  bool waitFor(double ms) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!finished_.wait_for(lock, std::chrono::duration<double, std::milli>(ms), [this] { return done_; }))
      return false;
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
    return true;
  }

  // Waits for the task started last; rethrows what it threw.
  void wait() {
    std::unique_lock<std::mutex> lock(mutex_);
    finished_.wait(lock, [this] { return done_; });
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [this] { return stop_ || task_; });
      if (stop_) return;
      std::function<void()> task = std::move(task_);
      task_ = nullptr;
      lock.unlock();
#if defined(__linux__) && defined(SCHED_IDLE)
      if (idle_priority_) {  // lowering is always allowed; a boost() of the last task is undone here
        sched_param p{};
        p.sched_priority = 0;
        pthread_setschedparam(pthread_self(), SCHED_IDLE, &p);  // threads it starts (OpenMP) inherit it
      }
#endif
      std::exception_ptr error;
      try {
        task();
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      error_ = error;
      done_ = true;
      finished_.notify_all();
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  std::function<void()> task_;
  std::exception_ptr error_;
  bool done_ = true, stop_ = false;
  bool idle_priority_ = false;
  std::thread thread_;
};

}  // namespace inc
