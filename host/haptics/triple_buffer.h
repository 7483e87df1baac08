// Lock-free single-producer single-consumer triple buffer: the haptic thread never waits on the simulation.
#pragma once

#include <atomic>
#include <cstdint>

namespace inc {

// The writer fills its private back slot, then publishes it with one atomic exchange with the shared
// middle slot; the reader, when the middle slot holds fresh data, exchanges it with its private front
// slot. Neither side ever blocks or spins, each slot is touched by one thread at a time (no data race,
// any copyable T), and the reader always gets the newest complete value. publishes() counts versions
// so the reader can tell how old its value is.
template <typename T>
class TripleBuffer {
 public:
  TripleBuffer() = default;
  explicit TripleBuffer(const T& initial) { reset(initial); }
  // Sets all slots; only while no other thread uses the buffer (set-up).
  void reset(const T& initial) { slots_[0] = slots_[1] = slots_[2] = initial; }

  // Writer side (one thread).
  T& back() { return slots_[back_]; }
  void publish() {
    const std::uint8_t old = middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
    back_ = old & kIndex;
    version_.fetch_add(1, std::memory_order_release);
  }
  void write(const T& value) {
    back() = value;
    publish();
  }

  // Reader side (one other thread). Returns true when a newer value arrived since the last call.
  bool update() {
    if ((middle_.load(std::memory_order_acquire) & kFresh) == 0) return false;
    const std::uint8_t old = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = old & kIndex;
    return true;
  }
  const T& front() const { return slots_[front_]; }
  // Number of publish() calls so far (any thread).
  std::uint64_t publishes() const { return version_.load(std::memory_order_acquire); }

 private:
  static constexpr std::uint8_t kIndex = 3, kFresh = 4;
  T slots_[3]{};
  std::uint8_t back_ = 0;                // writer-owned
  std::uint8_t front_ = 1;               // reader-owned
  std::atomic<std::uint8_t> middle_{2};  // shared: index | fresh bit
  std::atomic<std::uint64_t> version_{0};
};

}  // namespace inc
