// Haptic loop implementation: scheduling (sleep then spin), safety chain, recording, statistics.
#include "host/haptics/haptic_loop.h"

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <future>
#include <memory>

#include "model/input_error.h"
#include "physics/haptic_safety.h"

namespace inc {

namespace {
std::int64_t steadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
std::atomic<std::uint64_t> g_threads_started{0};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(q * double(v.size())) - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}
}  // namespace

SteadyClock::SteadyClock(double spin_margin_s) : spin_margin_s_(spin_margin_s), origin_ns_(steadyNs()) {}

double SteadyClock::now_s() { return double(steadyNs() - origin_ns_) * 1e-9; }

void SteadyClock::sleepUntil(double t_s) {
  // steady_clock is CLOCK_MONOTONIC on Linux: sleep to an absolute time (no drift from computing a relative
  // one), again after an early return (a signal), so the spin below lasts at most spin_margin_s.
  const std::int64_t coarse_ns = origin_ns_ + std::int64_t((t_s - spin_margin_s_) * 1e9);
  while (steadyNs() < coarse_ns) {
    timespec ts;
    ts.tv_sec = static_cast<time_t>(coarse_ns / 1000000000);
    ts.tv_nsec = static_cast<long>(coarse_ns % 1000000000);
    if (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0 && errno != EINTR) break;
  }
  while (now_s() < t_s) {
  }
}

HapticLoop::HapticLoop(HapticDevice& device, ForceModel model, HapticLoopConfig config, HapticClock* clock)
    : device_(device), model_(std::move(model)), config_(config), clock_(clock) {
  const char* f = "<haptic loop>";
  if (!(config_.rate_hz > 0.0) || !std::isfinite(config_.rate_hz) || config_.rate_hz > 1e5)
    throw InputError(f, "rate_hz", "must be in (0, 1e5]");
  if (!(config_.max_force_rate_n_per_s > 0.0)) throw InputError(f, "max_force_rate_n_per_s", "must be > 0");
  if (!(config_.stall_after_s > 0.0) || config_.stall_fade_s < 0.0)
    throw InputError(f, "stall_after_s", "stall_after_s must be > 0 and stall_fade_s >= 0");
  if (!(config_.late_tolerance >= 0.0)) throw InputError(f, "late_tolerance", "must be >= 0");
  if (!model_) throw InputError(f, "model", "no force model given");
  if (config_.realtime && (config_.realtime_priority < 1 || config_.realtime_priority > 99))
    throw InputError(f, "realtime_priority", "must be in [1, 99]");
  if (!(config_.spin_margin_s >= 0.0) || !(config_.realtime_spin_margin_s >= 0.0) || config_.spin_margin_s > 0.01 ||
      config_.realtime_spin_margin_s > 0.01)
    throw InputError(f, "spin_margin_s", "spin margins must be in [0, 10 ms]");
  if (!clock_) {
    auto steady = std::make_unique<SteadyClock>(config_.spin_margin_s);
    steady_ = steady.get();
    owned_clock_ = std::move(steady);
    clock_ = owned_clock_.get();
  }
  period_s_ = 1.0 / config_.rate_hz;
  records_.reserve(config_.record_capacity);
}

HapticLoop::~HapticLoop() { stop(); }

void HapticLoop::tick() {
  if (tick_ == 0 && last_wake_s_ < 0.0) {
    t0_s_ = clock_->now_s();
    next_deadline_s_ = t0_s_;
  }
  clock_->sleepUntil(next_deadline_s_);
  const double wake = clock_->now_s() - t0_s_;
  const double period = last_wake_s_ < 0.0 ? 0.0 : wake - last_wake_s_;
  if (last_wake_s_ >= 0.0 && period > (1.0 + config_.late_tolerance) * period_s_) ++missed_;
  last_wake_s_ = wake;

  ForceRequest req;
  req.tick = tick_;
  req.t_s = wake;
  req.dt_s = period_s_;
  req.sample = device_.read(tick_, wake);
  const ForceResult res = model_(req);
  // Safety chain: stall fade, clamp to the device maximum, rate limit from the last output.
  Vec3d f = res.force_n;
  if (res.data_time_s >= 0.0)
    f = f * stallFadeGain(wake - res.data_time_s, config_.stall_after_s, config_.stall_fade_s);
  f = clampForce(f, device_.maxForce_n());
  f = rateLimitForce(last_force_n_, f, config_.max_force_rate_n_per_s, period_s_);
  device_.writeForce(f);
  last_force_n_ = f;
  const double compute = clock_->now_s() - t0_s_ - wake;

  if (records_.size() < records_.capacity()) {
    TickRecord r;
    r.t_s = wake;
    r.period_s = period;
    r.compute_s = compute;
    r.sample = req.sample;
    r.model_force_n = res.force_n;
    r.force_n = f;
    records_.push_back(r);
  }
  HapticStatus& st = status_.back();
  st.tick = tick_;
  st.t_s = wake;
  st.sample = req.sample;
  st.force_n = f;
  st.last_period_s = period;
  st.last_compute_s = compute;
  st.missed = missed_;
  status_.publish();

  ++tick_;
  next_deadline_s_ += period_s_;
  // Fallen a whole period behind: drop the lost deadlines instead of firing a burst of late ticks.
  const double now = clock_->now_s();
  if (now > next_deadline_s_ + period_s_) {
    const double lost = std::floor((now - next_deadline_s_) / period_s_);
    skipped_ += static_cast<std::uint64_t>(lost);
    next_deadline_s_ += lost * period_s_;
  }
}

void HapticLoop::runTicks(std::uint64_t n) {
  for (std::uint64_t i = 0; i < n; ++i) tick();
}

// Runs on the loop's own thread: real-time policy when permitted, timer slack, CPU pinning.
HapticScheduling HapticLoop::setUpThreadScheduling() {
  HapticScheduling out;
  out.spin_margin_s = config_.spin_margin_s;
  // Timer slack: the kernel may otherwise delay a normal thread's wake-up by up to 50 us to batch timers.
  (void)prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  if (config_.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(config_.cpu, &set);
    const int e = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (e == 0)
      out.cpu = config_.cpu;
    else
      out.message += "CPU " + std::to_string(config_.cpu) + " pinning refused (" + std::strerror(e) + "); ";
  }
  if (config_.realtime) {
    sched_param p{};
    p.sched_priority = config_.realtime_priority;
    const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
    if (e == 0) {
      out.realtime = true;
      out.priority = config_.realtime_priority;
      out.spin_margin_s = config_.realtime_spin_margin_s;
      out.message += "SCHED_FIFO priority " + std::to_string(out.priority);
    } else {
      out.message += std::string("SCHED_FIFO refused (") + std::strerror(e) +
                     "): normal scheduling; run as root, grant CAP_SYS_NICE or raise the rtprio limit "
                     "(ulimit -r) for a steadier period";
    }
  } else {
    out.message += "normal scheduling (realtime off)";
  }
  if (steady_) steady_->setSpinMargin(out.spin_margin_s);
  return out;
}

void HapticLoop::start() {
  if (running_.exchange(true)) return;
  stop_.store(false);
  // Touch the record storage now so that the loop never takes a page fault on it.
  const std::size_t kept = records_.size();
  records_.resize(records_.capacity());
  records_.resize(kept);
  g_threads_started.fetch_add(1, std::memory_order_relaxed);
  std::promise<HapticScheduling> ready;
  std::future<HapticScheduling> result = ready.get_future();
  thread_ = std::thread([this, ready = std::move(ready)]() mutable {
    ready.set_value(setUpThreadScheduling());
    while (!stop_.load(std::memory_order_relaxed)) tick();
  });
  scheduling_ = result.get();
}

void HapticLoop::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  running_.store(false);
}

std::uint64_t hapticLoopThreadsStarted() { return g_threads_started.load(std::memory_order_relaxed); }

PeriodStats computePeriodStats(const std::vector<TickRecord>& records, double nominal_s, double late_tolerance) {
  PeriodStats s;
  s.nominal_s = nominal_s;
  s.ticks = records.size();
  std::vector<double> periods, computes;
  periods.reserve(records.size());
  computes.reserve(records.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < records.size(); ++i) {
    computes.push_back(records[i].compute_s);
    if (records[i].compute_s > nominal_s) ++s.overruns;
    if (i == 0) continue;
    periods.push_back(records[i].period_s);
    sum += records[i].period_s;
    if (records[i].period_s > (1.0 + late_tolerance) * nominal_s) ++s.missed;
  }
  s.p50_s = percentile(periods, 0.5);
  s.p99_s = percentile(periods, 0.99);
  s.max_s = periods.empty() ? 0.0 : *std::max_element(periods.begin(), periods.end());
  s.mean_s = periods.empty() ? 0.0 : sum / double(periods.size());
  s.compute_p50_s = percentile(computes, 0.5);
  s.compute_p99_s = percentile(computes, 0.99);
  s.compute_max_s = computes.empty() ? 0.0 : *std::max_element(computes.begin(), computes.end());
  return s;
}

PeriodStats HapticLoop::stats() const {
  PeriodStats s = computePeriodStats(records_, period_s_, config_.late_tolerance);
  s.skipped = skipped_;
  return s;
}

void writeTickForces(const std::string& path, const std::vector<TickRecord>& records) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw InputError(path, "", "cannot open the tick force file for writing");
  std::fprintf(f, "# tick t_s model_fx model_fy model_fz sent_fx sent_fy sent_fz (N; hex floats: bit-exact)\n");
  for (std::size_t i = 0; i < records.size(); ++i) {
    const TickRecord& r = records[i];
    std::fprintf(f, "%zu %a %a %a %a %a %a %a\n", i, r.t_s, r.model_force_n.x, r.model_force_n.y, r.model_force_n.z,
                 r.force_n.x, r.force_n.y, r.force_n.z);
  }
  if (std::fclose(f) != 0) throw InputError(path, "", "writing the tick force file failed");
}

Trajectory HapticLoop::recordedTrajectory() const {
  Trajectory tr;
  tr.samples.reserve(records_.size());
  for (std::size_t i = 0; i < records_.size(); ++i) {
    DeviceSample s = records_[i].sample;
    s.t_s = double(i) * period_s_;
    tr.samples.push_back(s);
  }
  return tr;
}

}  // namespace inc
