// Test fixture: holds the dissection's idle-priority tasks (idleWorkerGate, host/cut/cut_stroke_end.h) as a busy
// machine would starve them.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>

#include "host/cut/cut_stroke_end.h"

namespace inc::cuttest {

// Holds the dissection's idle-priority tasks (idleWorkerGate) until released; releases and clears the gate when it
// goes out of scope (declare it after the simulation: it must release before the simulation joins its workers).
class HeldIdleWorkers {
 public:
  HeldIdleWorkers() {
    idleWorkerGate() = [this] {
      std::unique_lock<std::mutex> lock(mutex_);
      ++held_;
      // Bounded, so that a build that waits for held workers fails its test instead of hanging.
      open_.wait_for(lock, std::chrono::seconds(60), [this] { return released_; });
    };
  }
  ~HeldIdleWorkers() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      released_ = true;
    }
    open_.notify_all();
    idleWorkerGate() = nullptr;
  }
  int held() {
    std::lock_guard<std::mutex> lock(mutex_);
    return held_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable open_;
  bool released_ = false;
  int held_ = 0;
};

}  // namespace inc::cuttest
