// Queries the CUDA runtime for usable devices without ever throwing (absent GPU is a normal case).
#include <cuda_runtime.h>

#include <algorithm>
#include <vector>

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

double measureCopyBandwidthGbs() {
  int n = 0;
  if (cudaGetDeviceCount(&n) != cudaSuccess || n == 0) {
    cudaGetLastError();
    return 0.0;
  }
  std::size_t free_b = 0, total_b = 0;
  if (cudaMemGetInfo(&free_b, &total_b) != cudaSuccess) return 0.0;
  const std::size_t bytes = std::min<std::size_t>(std::size_t(1) << 30, free_b / 4);
  void *a = nullptr, *b = nullptr;
  cudaEvent_t e0 = nullptr, e1 = nullptr;
  double gbs = 0.0;
  if (bytes >= (std::size_t(1) << 20) && cudaMalloc(&a, bytes) == cudaSuccess && cudaMalloc(&b, bytes) == cudaSuccess &&
      cudaEventCreate(&e0) == cudaSuccess && cudaEventCreate(&e1) == cudaSuccess &&
      cudaMemset(a, 1, bytes) == cudaSuccess && cudaMemcpy(b, a, bytes, cudaMemcpyDeviceToDevice) == cudaSuccess) {
    std::vector<float> ms;
    for (int k = 0; k < 10; ++k) {
      float t = 0.f;
      if (cudaEventRecord(e0) != cudaSuccess || cudaMemcpy(b, a, bytes, cudaMemcpyDeviceToDevice) != cudaSuccess ||
          cudaEventRecord(e1) != cudaSuccess || cudaEventSynchronize(e1) != cudaSuccess ||
          cudaEventElapsedTime(&t, e0, e1) != cudaSuccess)
        break;
      ms.push_back(t);
    }
    if (!ms.empty()) {
      std::sort(ms.begin(), ms.end());
      const double med = ms[ms.size() / 2];
      if (med > 0) gbs = 2.0 * double(bytes) / (med * 1e-3) / 1e9;
    }
  }
  if (e0) cudaEventDestroy(e0);
  if (e1) cudaEventDestroy(e1);
  if (a) cudaFree(a);
  if (b) cudaFree(b);
  cudaGetLastError();  // a failed allocation above is not an error of the caller's
  return gbs;
}

}  // namespace inc::cuda
