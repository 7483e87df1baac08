// Checking wrappers for every CUDA API call and kernel launch: failures throw with file and line.
#pragma once

#include <cuda_runtime.h>

#include <stdexcept>
#include <string>

namespace inc::cuda {

[[noreturn]] inline void throwCudaError(cudaError_t err, const char* what, const char* file, int line) {
  throw std::runtime_error(std::string("CUDA error at ") + file + ":" + std::to_string(line) + " in " + what + ": " +
                           cudaGetErrorName(err) + " (" + cudaGetErrorString(err) + ")");
}

inline void check(cudaError_t err, const char* what, const char* file, int line) {
  if (err != cudaSuccess) throwCudaError(err, what, file, line);
}

}  // namespace inc::cuda

// Wrap every runtime API call: INC_CUDA(cudaMalloc(&p, n));
#define INC_CUDA(call) ::inc::cuda::check((call), #call, __FILE__, __LINE__)
// After every launch: checks the launch configuration error (asynchronous faults surface at the next sync).
#define INC_CUDA_LAUNCH(what) ::inc::cuda::check(cudaGetLastError(), what, __FILE__, __LINE__)
