// Geometric growth of a DeviceBuffer that keeps its live prefix (appending into preallocated device capacity).
#pragma once

#include <cstddef>
#include <utility>

#include "kernels/cuda_check.h"
#include "kernels/device_buffer.h"

namespace inc::cuda {

template <typename U>
std::size_t capacityOf(const DeviceBuffer<U>& b) {
  return b.capacityBytes() / sizeof(U);
}

// Makes room for `need` elements (capacity 2 x need, so that appends reallocate O(log) times), keeping the
// first `keep` elements and the size. Returns true when it reallocated: the only case that synchronises the
// device (no kernel may still use the old allocation when it is freed; the copy is device to device).
template <typename U>
bool growKeep(DeviceBuffer<U>& b, std::size_t need, std::size_t keep) {
  if (need <= capacityOf(b)) return false;
  INC_CUDA(cudaDeviceSynchronize());
  const std::size_t size = b.size();
  DeviceBuffer<U> nb;
  nb.resize(2 * need);
  if (keep) INC_CUDA(cudaMemcpy(nb.data(), b.data(), keep * sizeof(U), cudaMemcpyDeviceToDevice));
  b = std::move(nb);
  b.resize(size);
  return true;
}

}  // namespace inc::cuda
