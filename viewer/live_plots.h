// The viewer's live plots: histories of frame rate, step and stage times, haptic loop rate and p99, energies,
// particle count and model counters, fed from the simulation's snapshots and drawn with ImGui.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "viewer/sim_runner.h"

namespace inc::viewer {

// A fixed-length ring of samples for ImGui's PlotLines.
class History {
 public:
  explicit History(std::size_t length = 240) : values_(length, 0.0f) {}
  void push(double v);
  float last() const { return last_; }
  std::size_t count() const { return count_; }  // samples pushed so far
  // The k-th newest sample (0: the last); k < min(count(), length).
  float recent(std::size_t k) const;
  void plot(const char* label, const char* unit) const;  // ImGui; call inside a window

 private:
  std::vector<float> values_;
  std::size_t offset_ = 0, count_ = 0;
  float last_ = 0.0f;
};

// Counter names a model uses for its haptic loop (FrameReport::counters).
inline constexpr const char* kHapticRateCounter = "haptic_hz";
inline constexpr const char* kHapticP99Counter = "haptic_p99_ms";

class LivePlots {
 public:
  void pushFrameRate(double fps) { fps_.push(fps); }
  // One published simulation frame: step and stage times, haptic counters, energies, particles, counters.
  void push(const SimSnapshot& s);

  void drawTiming() const;   // fps, step, each stage (ms)
  void drawHaptics() const;  // haptic loop rate and period p99, or why there are none
  void drawEnergy() const;   // kinetic, elastic, potential, total, max |u|, particles, other counters

  const History& fps() const { return fps_; }
  const History& step() const { return step_; }
  const History* stage(const std::string& name) const;
  const History* counter(const std::string& name) const;
  bool hasHaptics() const { return haptic_hz_.count() > 0; }
  const History& hapticRate() const { return haptic_hz_; }
  const History& hapticP99() const { return haptic_p99_; }
  const History& kinetic() const { return kinetic_; }
  const History& elastic() const { return elastic_; }
  const History& potential() const { return potential_; }
  const History& total() const { return total_; }
  const History& particles() const { return particles_; }

 private:
  History fps_, step_, haptic_hz_, haptic_p99_, kinetic_, elastic_, potential_, total_, displacement_, particles_;
  std::map<std::string, History> stages_, counters_;
};

}  // namespace inc::viewer
