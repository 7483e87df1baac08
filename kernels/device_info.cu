// Queries the CUDA runtime for usable devices without ever throwing (absent GPU is a normal case).
#include <cuda_runtime.h>

#include "kernels/device_info.h"

namespace inc::cuda {

DeviceReport queryDevices() {
  DeviceReport r;
  r.compiled = true;
  int n = 0;
  cudaError_t err = cudaGetDeviceCount(&n);
  if (err != cudaSuccess) {
    r.error = std::string(cudaGetErrorName(err)) + ": " + cudaGetErrorString(err);
    cudaGetLastError();  // clear the sticky error so later queries start clean
    return r;
  }
  if (n == 0) {
    r.error = "no CUDA device found";
    return r;
  }
  cudaDeviceProp p{};
  err = cudaGetDeviceProperties(&p, 0);
  if (err != cudaSuccess) {
    r.error = std::string(cudaGetErrorName(err)) + ": " + cudaGetErrorString(err);
    return r;
  }
  r.device_count = n;
  r.name = p.name;
  r.sm_major = p.major;
  r.sm_minor = p.minor;
  r.multiprocessors = p.multiProcessorCount;
  r.global_memory_bytes = p.totalGlobalMem;
  int mem_clock_khz = 0, bus_bits = 0;
  cudaDeviceGetAttribute(&mem_clock_khz, cudaDevAttrMemoryClockRate, 0);
  cudaDeviceGetAttribute(&bus_bits, cudaDevAttrGlobalMemoryBusWidth, 0);
  r.peak_bandwidth_gbs = 2.0 * mem_clock_khz * 1e3 * (bus_bits / 8.0) / 1e9;  // double data rate
  return r;
}

}  // namespace inc::cuda
