// Page-locked host staging for the small per-frame copies (count read-backs, a grasp's targets): an asynchronous copy
// on a stream instead of a synchronous cudaMemcpy from pageable memory.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <cstring>

#include "kernels/cuda_check.h"

namespace inc::cuda {

// A synchronous cudaMemcpy from or to pageable memory costs ~10 us however few its bytes (kernels/bulk_upload.h);
// the tearing frame reads two counts back and the PBD frame its summary, every frame. One buffer per use: an
// upload's bytes stay untouched until the copy has run (the owner synchronises its stream before the next one).
class PinnedStaging {
 public:
  PinnedStaging() = default;
  PinnedStaging(const PinnedStaging&) = delete;
  PinnedStaging& operator=(const PinnedStaging&) = delete;
  ~PinnedStaging() {
    if (ptr_) cudaFreeHost(ptr_);  // no throw from a destructor
  }

  // n elements from device memory into host memory: queued on `stream`, waited for, copied out.
  template <typename U>
  void download(U* host, const U* device, std::size_t n, cudaStream_t stream) {
    const std::size_t bytes = n * sizeof(U);
    if (bytes == 0) return;
    reserve(bytes);
    INC_CUDA(cudaMemcpyAsync(ptr_, device, bytes, cudaMemcpyDeviceToHost, stream));
    INC_CUDA(cudaStreamSynchronize(stream));
    std::memcpy(host, ptr_, bytes);
  }

  // n elements from device memory queued on `stream` into the staging, not waited for: take() copies them out once
  // the caller has synchronised `stream` (another wait already due, so the read-back costs no round trip of its own).
  template <typename U>
  void queueDownload(const U* device, std::size_t n, cudaStream_t stream) {
    const std::size_t bytes = n * sizeof(U);
    if (bytes == 0) return;
    reserve(bytes);
    INC_CUDA(cudaMemcpyAsync(ptr_, device, bytes, cudaMemcpyDeviceToHost, stream));
  }
  template <typename U>
  void take(U* host, std::size_t n) const {
    if (n) std::memcpy(host, ptr_, n * sizeof(U));
  }

  // n elements from host memory to device memory, queued on `stream` (not waited for: the staging keeps the
  // bytes, so the caller must synchronise `stream` before this staging's next upload).
  template <typename U>
  void upload(U* device, const U* host, std::size_t n, cudaStream_t stream) {
    const std::size_t bytes = n * sizeof(U);
    if (bytes == 0) return;
    reserve(bytes);
    std::memcpy(ptr_, host, bytes);
    INC_CUDA(cudaMemcpyAsync(device, ptr_, bytes, cudaMemcpyHostToDevice, stream));
  }

 private:
  void reserve(std::size_t bytes) {
    if (bytes <= cap_) return;
    if (ptr_) INC_CUDA(cudaFreeHost(ptr_));  // the owner's stream has finished with it (see upload)
    ptr_ = nullptr;
    cap_ = 0;
    INC_CUDA(cudaMallocHost(&ptr_, bytes));
    cap_ = bytes;
  }

  void* ptr_ = nullptr;
  std::size_t cap_ = 0;
};

}  // namespace inc::cuda
