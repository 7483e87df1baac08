// Launch geometry shared by the PBD kernels and the CUDA PBD backend: threads per block, grid sizes, reduction sizes
// and the live counts of a patched model.
#pragma once

#include <algorithm>
#include <cstdint>

namespace inc::cuda {

constexpr int kThreads = 128;
// Most blocks of a summary reduction (their partials are then reduced on the device in a fixed tree order, so the
// result is the same every run for the same counts). The grid grows with the count up to this (reduceBlocksFor):
// with a fixed 256 blocks of kThreads the residual pass over the 150k tearing sheet's ~450k constraints held 12 %
// of the H100's warps and took 19 us (ncu, 2026-11-27).
constexpr int kReduceBlocks = 1024;
inline int reduceBlocksFor(std::int64_t count) {
  return int(
      std::max<std::int64_t>(1, std::min<std::int64_t>(kReduceBlocks, (count + 4 * kThreads - 1) / (4 * kThreads))));
}

// The device copies of the counts a frame's kernels read (PbdCudaBackend::live_): entry 0 the particle count, entry
// 1 + b block b's constraint count. Written by one small launch before a frame whenever a patch changed them.
constexpr int kMaxLiveBlocks = 31;

inline unsigned blocksFor(std::int64_t n) { return unsigned((n + kThreads - 1) / kThreads); }

// The count a frame kernel stops at: its argument, or once the model was patched on the device the live count in
// device memory (PbdCudaBackend::live_), so that a captured frame stays valid across patches. Unpatched models pass
// no pointer and pay no load.
__device__ __forceinline__ int liveCount(const int* live, int count) { return live ? *live : count; }

}  // namespace inc::cuda
