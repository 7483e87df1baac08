// What CUDA devices this build can use; plain C++ so host code can ask without CUDA headers.
#pragma once

#include <cstddef>
#include <string>

namespace inc::cuda {

struct DeviceReport {
  bool compiled = false;  // was the CUDA backend compiled into this binary
  int device_count = 0;   // usable devices (0 when the driver or device is missing)
  std::string error;      // why none is usable, when device_count == 0
  std::string name;       // device 0
  int sm_major = 0, sm_minor = 0, multiprocessors = 0;
  std::size_t global_memory_bytes = 0;
  double peak_bandwidth_gbs = 0.0;  // from the memory clock and bus width (datasheet-style)
};

// Never throws: a missing driver or device is reported in the result.
DeviceReport queryDevices();

// The device's measured peak memory bandwidth (GB/s, bytes read + bytes written): the median of 10
// device-to-device copies of 1 GiB (or a quarter of the free memory) after a warm-up, timed with events.
// What the benchmarks' "of peak" divides by. 0 when no device is usable (never throws). ~0.1 s.
double measureCopyBandwidthGbs();

}  // namespace inc::cuda
