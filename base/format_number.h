// Numbers in messages and written files: the shortest text that reads back to the same double.
#pragma once

#include <charconv>
#include <cmath>
#include <string>

namespace inc {

// Formats a finite double as the shortest text that reads back to the same value.
inline std::string formatNumber(double v) {
  if (!std::isfinite(v)) return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

}  // namespace inc
