// The scripted haptic device: plays a trajectory by time or by tick.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "host/haptics/haptic_device.h"
#include "model/input_error.h"

namespace inc {

ScriptedDevice::ScriptedDevice(Trajectory trajectory, Mode mode, double max_force_n)
    : trajectory_(std::move(trajectory)), mode_(mode), max_force_n_(max_force_n) {
  validateTrajectory(trajectory_, "<scripted device>");
  if (!(max_force_n > 0.0) || !std::isfinite(max_force_n))
    throw InputError("<scripted device>", "max_force_n", "must be finite and > 0");
}

double ScriptedDevice::duration_s() const { return trajectory_.samples.back().t_s - trajectory_.samples.front().t_s; }

DeviceSample ScriptedDevice::read(std::uint64_t tick, double t_s) {
  const auto& s = trajectory_.samples;
  if (mode_ == Mode::kByTick) {
    DeviceSample out = s[tick < s.size() ? tick : s.size() - 1];
    return out;
  }
  DeviceSample out;
  if (t_s <= s.front().t_s) {
    out = s.front();
  } else if (t_s >= s.back().t_s) {
    out = s.back();
  } else {
    std::size_t lo = 0, hi = s.size() - 1;  // binary search: s[lo].t <= t < s[hi].t
    while (hi - lo > 1) {
      const std::size_t mid = (lo + hi) / 2;
      (s[mid].t_s <= t_s ? lo : hi) = mid;
    }
    const double w = (t_s - s[lo].t_s) / (s[hi].t_s - s[lo].t_s);
    out.position_m = s[lo].position_m + (s[hi].position_m - s[lo].position_m) * w;
    double qn = 0.0;
    const double sign = (s[lo].orientation[0] * s[hi].orientation[0] + s[lo].orientation[1] * s[hi].orientation[1] +
                         s[lo].orientation[2] * s[hi].orientation[2] + s[lo].orientation[3] * s[hi].orientation[3]) < 0
                            ? -1.0
                            : 1.0;  // shortest arc
    for (int k = 0; k < 4; ++k) {
      out.orientation[k] = (1.0 - w) * s[lo].orientation[k] + w * sign * s[hi].orientation[k];
      qn += out.orientation[k] * out.orientation[k];
    }
    qn = std::sqrt(qn);
    for (int k = 0; k < 4; ++k) out.orientation[k] /= qn;
    out.buttons = s[lo].buttons;
  }
  out.t_s = t_s;
  return out;
}

}  // namespace inc
