// What every backend reports about its cost: wall time per named stage and the memory it holds.
#pragma once

#include <cstddef>
#include <string>

namespace inc {

struct StageTime {
  std::string stage;  // a name from the paper's loop: "gradients", "stress", "forces", "integrate", ...
  double ms = 0.0;    // wall time of the stage summed over the frame's substeps (device events on the GPU)
};

struct MemoryReport {
  std::size_t device_bytes = 0;
  std::size_t host_bytes = 0;
};

}  // namespace inc
