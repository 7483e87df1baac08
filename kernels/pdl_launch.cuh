// Programmatic dependent launch (Hopper and later): a kernel scheduled while the one before it on the stream finishes.
#pragma once

#include <cuda_runtime.h>

#include <utility>

#include "kernels/cuda_check.h"

namespace inc::cuda {

// First statement of a kernel that may be launched with launchPdl: lets the next kernel on the stream be scheduled
// now (its blocks then wait in their own pdlEnter), then waits until the previous kernel has completed and its
// writes are visible. Nothing may touch global memory before it. Without a programmatic dependency (an ordinary
// launch, or before sm_90) both are no-ops.
__device__ __forceinline__ void pdlEnter() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
  asm volatile("griddepcontrol.launch_dependents;" ::: "memory");
  asm volatile("griddepcontrol.wait;" ::: "memory");
#endif
}

// Launches `kernel` on `stream`, with a programmatic dependency on the stream's previous kernel when `pdl` is set
// (the kernel must begin with pdlEnter). The dependency hides the launch latency between two dependent small
// kernels, which is most of a small model's frame; a stream capture records it as a programmatic graph edge.
template <typename... Params, typename... Args>
void launchPdl(bool pdl, void (*kernel)(Params...), unsigned grid, unsigned block, cudaStream_t stream, Args&&... args) {
  cudaLaunchConfig_t cfg{};
  cfg.gridDim = dim3(grid);
  cfg.blockDim = dim3(block);
  cfg.dynamicSmemBytes = 0;
  cfg.stream = stream;
  cudaLaunchAttribute attr[1];
  attr[0].id = cudaLaunchAttributeProgrammaticStreamSerialization;
  attr[0].val.programmaticStreamSerializationAllowed = 1;
  cfg.attrs = attr;
  cfg.numAttrs = pdl ? 1 : 0;
  INC_CUDA(cudaLaunchKernelEx(&cfg, kernel, std::forward<Args>(args)...));
}

}  // namespace inc::cuda
