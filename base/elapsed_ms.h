// Wall time since a steady-clock time point, in milliseconds: the host's stage timers.
#pragma once

#include <chrono>

namespace inc {

inline double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace inc
