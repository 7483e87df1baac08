// Capturing what a function enqueues on a stream into an executable CUDA graph (updated in place when it can be).
#pragma once

#include <cuda_runtime.h>

#include "kernels/cuda_check.h"
#include "model/device_capture_lock.h"

namespace inc::cuda {

// Captures the work `record()` enqueues on `stream` (thread-local capture mode) into `exec`. An existing `exec` is
// updated in place (cheaper than instantiating: a frame after a topology change usually differs only in counts
// and pointers); when the structure changed, or `exec` is null, a new one is instantiated. If `record` throws, the
// capture is ended and dropped so the stream stays usable, and the exception goes on.
template <typename Record>
void captureGraph(cudaStream_t stream, cudaGraphExec_t& exec, Record&& record) {
  // No worker's device load may run while the capture is open (model/device_capture_lock.h).
  const std::lock_guard<std::mutex> lock(deviceCaptureMutex());
  INC_CUDA(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal));
  cudaGraph_t graph = nullptr;
  try {
    record();
  } catch (...) {
    if (cudaStreamEndCapture(stream, &graph) == cudaSuccess && graph) cudaGraphDestroy(graph);
    throw;
  }
  INC_CUDA(cudaStreamEndCapture(stream, &graph));
  if (exec) {
    cudaGraphExecUpdateResultInfo info;
    if (cudaGraphExecUpdate(exec, graph, &info) != cudaSuccess) {
      (void)cudaGetLastError();  // not sticky: clear it and instantiate instead
      cudaGraphExecDestroy(exec);
      exec = nullptr;
    }
  }
  cudaError_t inst = cudaSuccess;
  if (!exec) inst = cudaGraphInstantiate(&exec, graph, 0);
  cudaGraphDestroy(graph);
  INC_CUDA(inst);
}

}  // namespace inc::cuda
