// Team barrier (spin, then sleep; stall detection) and the step-level back-off of TeamRunner.
#include "base/team.h"

#include <algorithm>

#include <omp.h>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace inc::cpu {

namespace {

using Clock = std::chrono::steady_clock;

// Spinning covers the usual wait (the other thread finishing its share of the phase, microseconds); past this
// a waiter sleeps so that it does not take the core from the thread it waits for.
constexpr std::chrono::microseconds kSpin{50};
// A wait past max(this, 2 x the waiter's own work since its previous barrier) is a stall, and so is a total
// wait over the step past (team size - 1) x the waiter's total work plus this.
// 10 ms: a member descheduled for a scheduler time slice or more. Shorter waits happen on an idle many-core
// host too (15 sleepers woken through one mutex), and treating them as stalls sent 16-thread frames to one thread.
constexpr std::chrono::microseconds kStallFloor{10000};

inline void cpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

}  // namespace

namespace detail {
int regionThreadId() { return omp_get_thread_num(); }
int regionThreadCount() { return omp_get_num_threads(); }
}  // namespace detail

Team::Team(int id, detail::TeamControl* control) : id_(id), control_(control), since_(Clock::now()) {}

void Team::barrier() const {
  if (!control_ || control_->active.load(std::memory_order_acquire) <= 1) return;
  detail::TeamControl& c = *control_;
  const Clock::time_point arrive = Clock::now();  // the one clock read of a barrier released while spinning
  worked_ += arrive - since_;
  const unsigned gen = c.generation.load(std::memory_order_acquire);
  if (c.arrived.fetch_add(1, std::memory_order_acq_rel) + 1 == c.threads.load(std::memory_order_relaxed)) {
    // Last to arrive: decide the team size of the next phases, then release the others.
    c.arrived.store(0, std::memory_order_relaxed);
    if (c.stall_seen.load()) c.active.store(1, std::memory_order_relaxed);
    c.generation.fetch_add(1);  // seq_cst: ordered before the sleepers check below
    if (c.sleepers.load() > 0) {
      const std::lock_guard<std::mutex> lock(c.mutex);
      c.wake.notify_all();
    }
    since_ = arrive;
    return;
  }
  // Latest release time before this wait counts as a stall (see Team): twice the work since the previous
  // barrier (at least kStallFloor), and no more than the step's allowance minus its waits so far. The allowance
  // is (threads - 1) x the step's work plus kStallFloor: a thread of a balanced team of T waits up to (T - 1)
  // times its own work before the team is no faster than one thread doing all T shares (on 16 cores a team
  // whose waits merely exceed its work is still ~8x faster than one thread; counting that as a stall sent
  // 16-thread frames to one thread).
  const Clock::duration phase_work = arrive - since_;
  const int others = std::max(1, c.threads.load(std::memory_order_relaxed) - 1);
  const Clock::time_point limit =
      arrive + std::min<Clock::duration>(
                   std::max<Clock::duration>(kStallFloor, 2 * phase_work),
                   std::max<Clock::duration>(others * worked_ + kStallFloor - waited_, Clock::duration(0)));
  bool released = false, timed = false;
  for (int k = 1;; ++k) {
    if (c.generation.load(std::memory_order_acquire) != gen) {
      released = true;
      break;
    }
    cpuRelax();
    if (k % 64 == 0) {
      timed = true;
      const Clock::time_point now = Clock::now();
      if (now - arrive > kSpin || now > limit) break;
    }
  }
  if (!released) {
    c.sleepers.fetch_add(1);  // seq_cst: a releaser that misses it has already moved the generation on
    std::unique_lock<std::mutex> lock(c.mutex);
    while (c.generation.load() == gen) {
      if (c.stall_seen.load(std::memory_order_relaxed)) {
        c.wake.wait(lock);
      } else if (c.wake.wait_until(lock, limit) == std::cv_status::timeout && c.generation.load() == gen) {
        c.stall_seen.store(true);
      }
    }
    lock.unlock();
    c.sleepers.fetch_sub(1);
  }
  // A wait released within the first few dozen spins (well under a microsecond) counts as work.
  since_ = timed || !released ? Clock::now() : arrive;
  waited_ += since_ - arrive;
}

int TeamRunner::chooseThreads(int wanted) {
  if (wanted <= 1) return 1;
  if (serial_left_ > 0) {
    --serial_left_;
    return 1;
  }
  return wanted;
}

void TeamRunner::record(bool stalled) {
  last_stalled_ = stalled;
  if (stalled) {
    ++stalled_steps_;
    serial_left_ = backoff_;
    backoff_ = std::min(2 * backoff_, kMaxBackoff);
  } else {
    backoff_ = kMinBackoff;
  }
}

}  // namespace inc::cpu
