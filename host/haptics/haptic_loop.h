// The haptic loop: a fixed-rate (1 kHz) force loop on its own thread, with recording and period statistics.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "host/haptics/haptic_device.h"
#include "host/haptics/triple_buffer.h"

namespace inc {

// Time source of the loop. SteadyClock is the real one; FakeClock makes the bookkeeping testable.
class HapticClock {
 public:
  virtual ~HapticClock() = default;
  virtual double now_s() = 0;
  virtual void sleepUntil(double t_s) = 0;
};

// std::chrono::steady_clock (CLOCK_MONOTONIC). sleepUntil is a hybrid wait: an absolute clock_nanosleep to
// spin_margin_s before the deadline (the OS wakes a thread late by tens of microseconds, more under load),
// then a spin on the clock of at most spin_margin_s (an early wake-up sleeps again rather than spinning
// longer), so the thread gives its core back for all but the last spin_margin_s of each period.
class SteadyClock : public HapticClock {
 public:
  explicit SteadyClock(double spin_margin_s = 2.0e-4);
  double now_s() override;
  void sleepUntil(double t_s) override;
  void setSpinMargin(double spin_margin_s) { spin_margin_s_ = spin_margin_s; }

 private:
  double spin_margin_s_;
  std::int64_t origin_ns_;
};

// Manual clock: sleepUntil jumps to the deadline; advance() stands for compute time.
class FakeClock : public HapticClock {
 public:
  double now_s() override { return t_s_; }
  void sleepUntil(double t_s) override {
    if (t_s > t_s_) t_s_ = t_s;
  }
  void advance(double dt_s) { t_s_ += dt_s; }

 private:
  double t_s_ = 0.0;
};

struct HapticLoopConfig {
  double rate_hz = 1000.0;                 // loop rate; period = 1 / rate_hz
  double max_force_rate_n_per_s = 1000.0;  // rate limiter: at 1 kHz, 1 N per tick at most
  double stall_after_s = 1.0 / 30.0;       // simulation data older than this starts the fade
  double stall_fade_s = 0.1;               // ... reaching zero force this much later
  double late_tolerance = 0.1;             // a period > (1 + tol) * nominal counts as a missed deadline
  std::size_t record_capacity = 600000;    // ticks recorded (preallocated and pre-touched: no allocation or page
                                           // fault in the loop)
  double spin_margin_s = 2.0e-4;           // SteadyClock spin margin under normal (time-shared) scheduling
  // Scheduling of the loop's own thread (start()): SCHED_FIFO at realtime_priority when the process may
  // (root / CAP_SYS_NICE / an rtprio limit), else the default policy with a message in scheduling().
  // Under SCHED_FIFO the thread preempts every normal thread the moment its sleep ends, so the spin margin
  // can be short; the thread still sleeps most of each period (it never starves the others).
  bool realtime = true;
  int realtime_priority = 80;  // 1..99
  double realtime_spin_margin_s = 5.0e-5;
  int cpu = -1;  // >= 0: pin the loop thread to this CPU
};

// How the loop's thread is scheduled (filled by start()).
struct HapticScheduling {
  bool realtime = false;  // SCHED_FIFO granted
  int priority = 0;       // its priority (0 under SCHED_OTHER)
  int cpu = -1;           // pinned CPU, -1: none
  double spin_margin_s = 0.0;
  std::string message;  // what was asked, what was granted and why not (e.g. "SCHED_FIFO refused: ...")
};

// What the force model is given each tick. dt_s is the nominal period (not the measured one) so that
// a replay computes the same forces whatever the real clock's jitter.
struct ForceRequest {
  std::uint64_t tick = 0;
  double t_s = 0.0;
  double dt_s = 0.0;
  DeviceSample sample;
};
// The model's answer: force on the hand (newtons) and the loop time (seconds) at which the simulation
// data it used was published; data_time_s < 0 means "no simulation data involved" (no stall fade).
struct ForceResult {
  Vec3d force_n;
  double data_time_s = -1.0;
};
using ForceModel = std::function<ForceResult(const ForceRequest&)>;

struct TickRecord {
  double t_s = 0.0;        // wake-up time of the tick, seconds since the loop started
  double period_s = 0.0;   // t_s minus the previous tick's t_s (0 for the first)
  double compute_s = 0.0;  // device read + model + safety + device write
  DeviceSample sample;
  Vec3d model_force_n;  // what the model asked for
  Vec3d force_n;        // what was sent after fade, clamp and rate limit
};

struct PeriodStats {
  std::uint64_t ticks = 0;
  double nominal_s = 0.0;
  double p50_s = 0.0, p99_s = 0.0, max_s = 0.0, mean_s = 0.0;
  double compute_p50_s = 0.0, compute_p99_s = 0.0, compute_max_s = 0.0;
  std::uint64_t missed = 0;    // periods longer than (1 + late_tolerance) * nominal
  std::uint64_t overruns = 0;  // ticks whose compute alone exceeded the nominal period
  std::uint64_t skipped = 0;   // deadlines dropped to resynchronise after falling a whole period behind
};
PeriodStats computePeriodStats(const std::vector<TickRecord>& records, double nominal_s, double late_tolerance);
// Writes one line per tick: `tick t_s model_fx model_fy model_fz sent_fx sent_fy sent_fz` (newtons, C99 hex floats:
// bit-exact), `#` comment header. A replay's model forces compare bit for bit with a recording's. Throws
// InputError(path, "", reason) when it cannot be written.
void writeTickForces(const std::string& path, const std::vector<TickRecord>& records);
// Loop threads started by HapticLoop::start() in this process (a scene without haptics starts none).
std::uint64_t hapticLoopThreadsStarted();

// Latest tick, published for the simulation and viewer threads (read with status().update()/front()).
struct HapticStatus {
  std::uint64_t tick = 0;
  double t_s = 0.0;
  DeviceSample sample;
  Vec3d force_n;
  double last_period_s = 0.0;
  double last_compute_s = 0.0;
  std::uint64_t missed = 0;
};

class HapticLoop {
 public:
  // clock == nullptr: a SteadyClock owned by the loop. Throws InputError for a bad config.
  HapticLoop(HapticDevice& device, ForceModel model, HapticLoopConfig config = {}, HapticClock* clock = nullptr);
  ~HapticLoop();
  HapticLoop(const HapticLoop&) = delete;
  HapticLoop& operator=(const HapticLoop&) = delete;

  // Runs n ticks on the calling thread (tests, replays).
  void runTicks(std::uint64_t n);
  // Runs on its own std::thread until stop(). Recording is read only after stop().
  // start() returns once the thread has set up its scheduling (see scheduling()).
  void start();
  void stop();
  bool running() const { return running_.load(); }
  const HapticScheduling& scheduling() const { return scheduling_; }

  const std::vector<TickRecord>& records() const { return records_; }
  PeriodStats stats() const;
  // Device trajectory of the recorded ticks (times = tick * period) for bit-exact replay (kByTick).
  Trajectory recordedTrajectory() const;
  TripleBuffer<HapticStatus>& status() { return status_; }
  double period_s() const { return period_s_; }

 private:
  void tick();
  HapticScheduling setUpThreadScheduling();
  HapticDevice& device_;
  ForceModel model_;
  HapticLoopConfig config_;
  HapticClock* clock_;
  std::unique_ptr<HapticClock> owned_clock_;
  SteadyClock* steady_ = nullptr;  // owned_clock_ when it is a SteadyClock (spin margin follows the scheduling)
  HapticScheduling scheduling_;
  double period_s_;
  double t0_s_ = 0.0;
  double next_deadline_s_ = 0.0;
  double last_wake_s_ = -1.0;
  std::uint64_t tick_ = 0;
  std::uint64_t missed_ = 0, skipped_ = 0;
  Vec3d last_force_n_;
  std::vector<TickRecord> records_;
  TripleBuffer<HapticStatus> status_;
  std::atomic<bool> stop_{false}, running_{false};
  std::thread thread_;
};

}  // namespace inc
