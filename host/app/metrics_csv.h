// Per-frame metrics CSV: time per stage, energies, max displacement, the NaN check and model counters.
#pragma once

#include <fstream>
#include <string>
#include <vector>

#include "host/sim/simulation_model.h"

namespace inc {

class MetricsCsv {
 public:
  explicit MetricsCsv(const std::string& path);  // throws InputError when the file cannot be created
  // Columns are fixed by the first row written (stage names and counters of the first frame).
  void write(long frame, double time_s, double wall_ms, const FrameReport& r);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ofstream out_;
  std::vector<std::string> stages_, counters_;
  bool header_written_ = false;
};

}  // namespace inc
