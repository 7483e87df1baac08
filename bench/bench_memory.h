// Per-row memory figures of the benchmarks: the process's peak resident set during a row and the device memory in use.
#pragma once

#include <malloc.h>
#include <sys/resource.h>

#include <fstream>
#include <string>

#include "model/backend.h"
#if INCISION_HAVE_CUDA
#include <cuda_runtime.h>

#include "kernels/cuda_check.h"
#endif

namespace inc::bench {

// Peak host memory per row: the kernel's high-water mark of the resident set (VmHWM) is reset before the row
// (Linux >= 4.0: write 5 to /proc/self/clear_refs, after malloc_trim returns freed heap pages), then read after
// it. The figure is the whole process (binary, OpenMP and CUDA runtimes included), not the model alone. Where
// the reset is not allowed it falls back to ru_maxrss, the peak since the process started (then monotone).
struct HostPeak {
  bool per_row = false;
  void reset() {
    malloc_trim(0);
    std::ofstream f("/proc/self/clear_refs");
    f << "5";
    f.flush();
    per_row = bool(f);
  }
  double mib() const {
    if (per_row) {
      std::ifstream st("/proc/self/status");
      std::string key;
      while (st >> key) {
        if (key == "VmHWM:") {
          double kib = 0;
          st >> kib;
          return kib / 1024.0;
        }
        st.ignore(1 << 12, '\n');
      }
    }
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
  }
};

// Device memory in use (MiB, all of the device: cudaMemGetInfo), 0 without CUDA.
inline double deviceUsedMiB(BackendKind be) {
#if INCISION_HAVE_CUDA
  if (be == BackendKind::Cuda) {
    size_t free_b = 0, total_b = 0;
    INC_CUDA(cudaMemGetInfo(&free_b, &total_b));
    return double(total_b - free_b) / 1048576.0;
  }
#endif
  (void)be;
  return 0.0;
}

}  // namespace inc::bench
