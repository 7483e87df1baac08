// Lock-free single-producer single-consumer ring: haptic-thread events (cut start/stop) to the simulation.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>

namespace inc {

// Capacity N - 1 items. push() fails (returns false, never blocks) when full; pop() when empty.
template <typename T, std::size_t N>
class SpscRing {
 public:
  bool push(const T& v) {
    const std::size_t h = head_.load(std::memory_order_relaxed), next = (h + 1) % N;
    if (next == tail_.load(std::memory_order_acquire)) return false;
    items_[h] = v;
    head_.store(next, std::memory_order_release);
    return true;
  }
  bool pop(T& out) {
    const std::size_t t = tail_.load(std::memory_order_relaxed);
    if (t == head_.load(std::memory_order_acquire)) return false;
    out = items_[t];
    tail_.store((t + 1) % N, std::memory_order_release);
    return true;
  }

 private:
  std::array<T, N> items_{};
  std::atomic<std::size_t> head_{0}, tail_{0};
};

}  // namespace inc
