// Many small host arrays into their device buffers at once: packed into one page-locked buffer, copied by
// asynchronous copies on one stream, waited for once.
#pragma once

#include <algorithm>

#include <cuda_runtime.h>

#include <cstddef>
#include <cstring>
#include <vector>

#include "kernels/cuda_check.h"
#include "kernels/device_buffer.h"

namespace inc::cuda {

// A synchronous cudaMemcpy from pageable memory costs ~10 us however few its bytes, and a model upload has ~80
// arrays (a cut uploads a new PBD model every frame the blade enters spheres). Here the host packs them, queues
// one asynchronous copy (or memset) per array and synchronises once in flush(). Destination buffers are resized
// when added (DeviceBuffer::resize: grown, never shrunk); their contents are valid after flush().
class BulkUpload {
 public:
  BulkUpload() = default;
  BulkUpload(const BulkUpload&) = delete;
  BulkUpload& operator=(const BulkUpload&) = delete;
  ~BulkUpload() {
    if (pinned_) cudaFreeHost(pinned_);  // no throw from a destructor
  }

  template <typename T>
  void add(DeviceBuffer<T>& dst, const T* src, std::size_t n) {
    dst.resize(n);
    if (n == 0) return;
    const std::size_t bytes = n * sizeof(T), offset = packed_.size();
    packed_.resize(offset + ((bytes + 15) / 16) * 16);  // 16-byte aligned pieces: full-speed DMA
    std::memcpy(packed_.data() + offset, src, bytes);
    ops_.push_back({dst.data(), offset, bytes, false});
  }
  template <typename T>
  void add(DeviceBuffer<T>& dst, const std::vector<T>& src) {
    add(dst, src.data(), src.size());
  }
  // dst resized to n elements, all bytes zero.
  template <typename T>
  void zero(DeviceBuffer<T>& dst, std::size_t n) {
    dst.resize(n);
    if (n) ops_.push_back({dst.data(), 0, n * sizeof(T), true});
  }

  // Queues every copy and memset on `stream` and waits for them (the page-locked buffer is reused next time).
  void flush(cudaStream_t stream) {
    if (packed_.size() > capacity_) {  // at least doubled: page-locking is slow, and a cut's uploads grow each frame
      const std::size_t cap = std::max(packed_.size() + packed_.size() / 4, 2 * capacity_);
      if (pinned_) INC_CUDA(cudaFreeHost(pinned_));
      pinned_ = nullptr;
      capacity_ = 0;
      INC_CUDA(cudaMallocHost(&pinned_, cap));
      capacity_ = cap;
    }
    if (!packed_.empty()) std::memcpy(pinned_, packed_.data(), packed_.size());
    for (const Op& op : ops_) {
      if (op.zero)
        INC_CUDA(cudaMemsetAsync(op.dst, 0, op.bytes, stream));
      else
        INC_CUDA(
            cudaMemcpyAsync(op.dst, static_cast<char*>(pinned_) + op.offset, op.bytes, cudaMemcpyHostToDevice, stream));
    }
    INC_CUDA(cudaStreamSynchronize(stream));
    packed_.clear();
    ops_.clear();
  }

  std::size_t pinnedBytes() const { return capacity_; }

 private:
  struct Op {
    void* dst;
    std::size_t offset, bytes;
    bool zero;
  };
  std::vector<char> packed_;
  std::vector<Op> ops_;
  void* pinned_ = nullptr;
  std::size_t capacity_ = 0;
};

}  // namespace inc::cuda
