// The CPU fallback's loop primitive: a static-schedule OpenMP parallel for (deterministic partition).
#pragma once

#include <cstdint>

namespace inc::cpu {

// Number of threads the CPU fallback uses (OMP_NUM_THREADS or the core count).
int threadCount();

// Calls body(i) for i in [0, n). Static schedule: each index always lands on the same thread for a
// given thread count, and bodies must only write their own outputs (gather, never scatter).
template <typename Body>
void parallelFor(std::int64_t n, Body&& body) {
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < n; ++i) body(i);
}

}  // namespace inc::cpu
