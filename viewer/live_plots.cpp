// Plot histories from simulation snapshots, and the Timing / Haptics / Energy panels that draw them.
#include "viewer/live_plots.h"

#include <cfloat>
#include <cstdio>

#include <imgui.h>

namespace inc::viewer {

void History::push(double v) {
  last_ = float(v);
  values_[offset_] = last_;
  offset_ = (offset_ + 1) % values_.size();
  ++count_;
}

float History::recent(std::size_t k) const {
  return values_[(offset_ + values_.size() - 1 - k % values_.size()) % values_.size()];
}

void History::plot(const char* label, const char* unit) const {
  char overlay[64];
  std::snprintf(overlay, sizeof overlay, "%.4g %s", double(last_), unit);
  ImGui::PlotLines(label, values_.data(), int(values_.size()), int(offset_), overlay, FLT_MAX, FLT_MAX, ImVec2(0, 40));
}

void LivePlots::push(const SimSnapshot& s) {
  step_.push(s.advance_ms);
  for (const auto& st : s.report.stages) stages_[st.stage].push(st.ms);
  const FrameReport& r = s.report;
  kinetic_.push(r.kinetic_energy);
  elastic_.push(r.elastic_energy);
  potential_.push(r.potential_energy);
  total_.push(r.kinetic_energy + r.elastic_energy + r.potential_energy);
  displacement_.push(r.max_displacement);
  particles_.push(double(s.particles));
  for (const auto& [k, v] : r.counters) {
    if (k == kHapticRateCounter)
      haptic_hz_.push(v);
    else if (k == kHapticP99Counter)
      haptic_p99_.push(v);
    else
      counters_[k].push(v);
  }
}

const History* LivePlots::stage(const std::string& name) const {
  auto it = stages_.find(name);
  return it == stages_.end() ? nullptr : &it->second;
}

const History* LivePlots::counter(const std::string& name) const {
  auto it = counters_.find(name);
  return it == counters_.end() ? nullptr : &it->second;
}

void LivePlots::drawTiming() const {
  fps_.plot("fps", "Hz");
  step_.plot("step", "ms");
  for (const auto& [name, h] : stages_) h.plot(name.c_str(), "ms");
}

void LivePlots::drawHaptics() const {
  if (!hasHaptics()) {
    ImGui::TextDisabled("no haptic loop in this model (no %s / %s counters)", kHapticRateCounter, kHapticP99Counter);
    return;
  }
  haptic_hz_.plot("loop rate", "Hz");
  if (haptic_p99_.count() > 0) haptic_p99_.plot("period p99", "ms");
}

void LivePlots::drawEnergy() const {
  kinetic_.plot("kinetic", "J");
  elastic_.plot("elastic", "J");
  potential_.plot("potential", "J");
  total_.plot("total", "J");
  displacement_.plot("max |u|", "m");
  particles_.plot("particles", "");
  for (const auto& [k, h] : counters_) h.plot(k.c_str(), "");
}

}  // namespace inc::viewer
