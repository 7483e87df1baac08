// What the simulation thread learns from a running haptic loop (tick times -> rate, periods) and tells it (data time).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "host/haptics/haptic_loop.h"
#include "host/haptics/spsc_ring.h"

namespace inc {

// The loop's rate and periods over its newest ticks, for the model counters haptic_hz, haptic_p50_ms, ...
struct HapticWindow {
  double rate_hz = 0.0;     // ticks per second over the window (1 / mean period)
  double p50_ms = 0.0;      // median of the window's periods
  double p99_ms = 0.0;      // 99th percentile of the window's periods
  double max_ms = 0.0;      // longest period of the window
  std::size_t periods = 0;  // periods in the window
  std::uint64_t ticks = 0;  // ticks seen so far
};

// Lock-free on the haptic side: stamp() pushes the tick time into an SPSC ring (never blocks; when the ring is
// full the time is dropped and a NaN marker goes in before the next time that fits, so the consumer restarts its
// period chain there and a gap never counts as one period) and
// stamps the force with the simulation's data time (the stall fade of the safety chain). The simulation thread
// calls frameDone() after each frame: it drains the ring, publishes the newest tick time as the data time and
// returns the window statistics.
class HapticLink {
 public:
  explicit HapticLink(std::size_t window_periods = 1000) : ring_(std::max<std::size_t>(window_periods, 1)) {
    sorted_.reserve(ring_.size());
  }

  // Haptic thread, each tick.
  ForceResult stamp(ForceResult r, double t_s) {
    const double data = data_time_s_.load(std::memory_order_acquire);
    if (data >= 0.0) r.data_time_s = r.data_time_s >= 0.0 ? std::min(r.data_time_s, data) : data;
    if (gap_) {
      if (!ticks_.push(std::numeric_limits<double>::quiet_NaN())) return r;  // still full: drop this time too
      gap_ = false;
    }
    if (!ticks_.push(t_s)) gap_ = true;
    return r;
  }

  // Simulation thread, after each frame (one thread only).
  HapticWindow frameDone() {
    double t;
    while (ticks_.pop(t)) {
      if (std::isnan(t)) {  // ticks were dropped here
        have_last_ = false;
        continue;
      }
      ++seen_;
      if (have_last_) {
        ring_[head_] = t - last_;
        head_ = (head_ + 1) % ring_.size();
        count_ = std::min(count_ + 1, ring_.size());
      }
      last_ = t;
      have_last_ = true;
    }
    if (have_last_) data_time_s_.store(last_, std::memory_order_release);
    HapticWindow w;
    w.ticks = seen_;
    w.periods = count_;
    if (count_ == 0) return w;
    sorted_.assign(ring_.begin(), ring_.begin() + std::ptrdiff_t(count_));
    double sum = 0.0, longest = 0.0;
    for (double p : sorted_) {
      sum += p;
      longest = std::max(longest, p);
    }
    w.rate_hz = sum > 0.0 ? double(count_) / sum : 0.0;
    w.max_ms = 1e3 * longest;
    // The same percentiles as computePeriodStats: the ceil(q n)-th smallest.
    for (const double q : {0.99, 0.5}) {
      const std::size_t k = std::min(count_ - 1, std::size_t(std::ceil(q * double(count_))) - 1);
      std::nth_element(sorted_.begin(), sorted_.begin() + std::ptrdiff_t(k), sorted_.end());
      (q > 0.9 ? w.p99_ms : w.p50_ms) = 1e3 * sorted_[k];
    }
    return w;
  }

  // The loop time the simulation data was last published at (-1: never; then no stall fade).
  void setDataTime(double t_s) { data_time_s_.store(t_s, std::memory_order_release); }

 private:
  SpscRing<double, 8192> ticks_;
  std::atomic<double> data_time_s_{-1.0};
  bool gap_ = false;  // haptic thread: a time was dropped since the last one that fitted
  // Simulation-thread state.
  std::vector<double> ring_, sorted_;  // the newest periods (circular) and a scratch copy
  std::size_t head_ = 0, count_ = 0;
  double last_ = 0.0;
  bool have_last_ = false;
  std::uint64_t seen_ = 0;
};

}  // namespace inc
