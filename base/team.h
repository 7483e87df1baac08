// A team of threads kept for one multi-phase step (one OpenMP parallel region, barriers between phases) that carries on
// with the lead thread alone when a barrier stalls.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace inc::cpu {

namespace detail {

// Shared by the threads of one team run.
struct TeamControl {
  std::atomic<int> threads{1};  // threads of the team
  std::atomic<int> active{1};   // threads that take part in phases: `threads`, or 1 after a stall
  std::atomic<bool> stall_seen{false};
  alignas(64) std::atomic<int> arrived{0};
  alignas(64) std::atomic<unsigned> generation{0};
  std::atomic<int> sleepers{0};
  std::mutex mutex;
  std::condition_variable wake;
};

int regionThreadId();
int regionThreadCount();

}  // namespace detail

// One thread's handle inside TeamRunner::run. Phases split their items with begin/end; barrier() separates
// phases where one thread reads what another wrote. Every thread must call the same sequence of barriers.
//
// A barrier spins briefly, then sleeps. The team has stalled when a waiter has waited longer than it worked:
// in one wait (past twice its work since its previous barrier, and at least 10 ms: a team member was
// descheduled) or over the step so far (more than (team size - 1) x its work plus 10 ms: many short waits,
// the team no faster than one thread). That happens on a loaded machine (other processes, a second test process with
// its own team). From the barrier where a stall is noticed on, the team has size 1: the lead thread does every
// remaining phase alone, the others get empty ranges and their barriers return at once. Phase results do not
// depend on who computes which item, so the step's result is unchanged.
class Team {
 public:
  Team() = default;
  Team(int id, detail::TeamControl* control);

  int id() const { return id_; }
  bool lead() const { return id_ == 0; }
  // Threads taking part in phases now; changes only inside a barrier.
  int size() const { return control_ ? control_->active.load(std::memory_order_acquire) : 1; }
  // This thread's contiguous share [begin, end) of n items (static: the same split for a given size; empty
  // for a thread that no longer takes part).
  std::int64_t begin(std::int64_t n) const { return share(n, id_); }
  std::int64_t end(std::int64_t n) const { return share(n, id_ + 1); }
  void barrier() const;

 private:
  std::int64_t share(std::int64_t n, int k) const {
    const int s = size();
    return k >= s ? n : n * k / s;
  }

  int id_ = 0;
  detail::TeamControl* control_ = nullptr;
  mutable std::chrono::steady_clock::time_point since_{};  // end of this thread's previous barrier
  mutable std::chrono::steady_clock::duration worked_{};   // this thread's time outside barriers, this step
  mutable std::chrono::steady_clock::duration waited_{};   // and inside them
};

// Runs multi-phase steps on a team. After a step whose team stalled, the next steps run on the calling thread
// alone (8 steps, doubling after each further stalled team step up to 512; reset by a step without a stall),
// so a loaded machine costs one stall now and then instead of one per barrier.
class TeamRunner {
 public:
  // Runs body(const Team&) on `threads` threads of one parallel region, or on the calling thread alone when
  // threads <= 1 or while backing off after a stall.
  template <typename Body>
  void run(int threads, Body&& body);

  int lastThreads() const { return last_threads_; }  // team size the last step started with
  bool lastStalled() const { return last_stalled_; }
  std::int64_t stalledSteps() const { return stalled_steps_; }

 private:
  static constexpr int kMinBackoff = 8;
  static constexpr int kMaxBackoff = 512;
  int chooseThreads(int wanted);
  void record(bool stalled);

  int backoff_ = kMinBackoff;
  int serial_left_ = 0;
  int last_threads_ = 1;
  bool last_stalled_ = false;
  std::int64_t stalled_steps_ = 0;
};

template <typename Body>
void TeamRunner::run(int threads, Body&& body) {
  threads = chooseThreads(threads);
  last_threads_ = threads;
  if (threads <= 1) {
    const Team solo;
    body(solo);
    last_stalled_ = false;
    return;
  }
  detail::TeamControl control;
  control.threads.store(threads);
  control.active.store(threads);
#pragma omp parallel num_threads(threads)
  {
    const int id = detail::regionThreadId();
    if (detail::regionThreadCount() == threads) {
      const Team t(id, &control);
      body(t);
    } else if (id == 0) {  // fewer threads than asked (nested or limited OpenMP): the lead alone
      const Team solo;
      body(solo);
    }
  }
  record(control.stall_seen.load());
}

}  // namespace inc::cpu
