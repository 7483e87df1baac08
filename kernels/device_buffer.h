// Owning typed device allocation (RAII) with checked copies; the unit of device-resident SoA data.
#pragma once

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

#include "kernels/cuda_check.h"

namespace inc::cuda {

template <typename T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  explicit DeviceBuffer(std::size_t n) { resize(n); }
  ~DeviceBuffer() { release(); }
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  DeviceBuffer(DeviceBuffer&& o) noexcept
      : ptr_(std::exchange(o.ptr_, nullptr)),
        size_(std::exchange(o.size_, 0)),
        capacity_(std::exchange(o.capacity_, 0)) {}
  DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
    if (this != &o) {
      release();
      ptr_ = std::exchange(o.ptr_, nullptr);
      size_ = std::exchange(o.size_, 0);
      capacity_ = std::exchange(o.capacity_, 0);
    }
    return *this;
  }

  // Grows geometrically and never shrinks, so that repeated rebuilds do not re-allocate: the first allocation
  // holds n + n/4, a later one at least twice the last (a cut's point set grows every frame; each cudaFree
  // synchronises the device and cudaMalloc costs host time, so few, larger steps are cheaper).
  void resize(std::size_t n) {
    if (n > capacity_) {
      const std::size_t cap = std::max(n + n / 4, 2 * capacity_);
      release();
      INC_CUDA(cudaMalloc(reinterpret_cast<void**>(&ptr_), cap * sizeof(T)));
      capacity_ = cap;
    }
    size_ = n;
  }
  void upload(const T* host, std::size_t n) {
    resize(n);
    if (n) INC_CUDA(cudaMemcpy(ptr_, host, n * sizeof(T), cudaMemcpyHostToDevice));
  }
  void upload(const std::vector<T>& host) { upload(host.data(), host.size()); }
  void download(T* host, std::size_t n) const {
    if (n) INC_CUDA(cudaMemcpy(host, ptr_, n * sizeof(T), cudaMemcpyDeviceToHost));
  }
  std::vector<T> download() const {
    std::vector<T> out(size_);
    download(out.data(), size_);
    return out;
  }
  void fillZero() {
    if (size_) INC_CUDA(cudaMemset(ptr_, 0, size_ * sizeof(T)));
  }

  T* data() { return ptr_; }
  const T* data() const { return ptr_; }
  std::size_t size() const { return size_; }
  std::size_t bytes() const { return size_ * sizeof(T); }
  std::size_t capacity() const { return capacity_; }
  std::size_t capacityBytes() const { return capacity_ * sizeof(T); }

 private:
  void release() {
    if (ptr_) cudaFree(ptr_);  // no throw from a destructor path; a failed free is not recoverable anyway
    ptr_ = nullptr;
    size_ = capacity_ = 0;
  }
  T* ptr_ = nullptr;
  std::size_t size_ = 0;
  std::size_t capacity_ = 0;
};

}  // namespace inc::cuda
