// Constraint-projection PBD kernels of the per-block frame and their host launch wrappers: per-kind, staged, generic
// and cluster-group projections, the Jacobi gather, attachments, cluster rotations.
#include "kernels/pbd_projection_kernels.cuh"

#include <cstddef>
#include <cstdint>

#include "kernels/cuda_check.h"
#include "kernels/pbd_group_projection.cuh"
#include "kernels/pbd_launch.cuh"
#include "kernels/pbd_particle_ops.cuh"
#include "physics/pbd_block.h"

namespace inc::cuda {

namespace {

// Each kernel is one loop of the CPU backend (cpu_fallback/pbd_solver_cpu.cpp) with the same physics calls.

template <typename T>
__global__ void attachKernel(int k, Vec3<T>* x, const T* w, const std::int32_t* ids, const Vec3<T>* from,
                             const Vec3<T>* to, const T* compliance, Vec3<T>* lambda, bool xpbd, T dt, T t) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q >= k) return;
  const std::int32_t id = ids[q];
  pbd::projectAttachment(x[id], w[id], pbd::lerp(from[q], to[q], t), compliance[q], xpbd, dt, lambda[q]);
}

template <typename T>
__global__ void projectAllKernel(pbd::BlockView<T> b, pbd::SolveContext<T> ctx, const int* live_count) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c >= liveCount(live_count, b.count)) return;
  pbd::projectConstraint(b, c, ctx);
}

// One kind's constraints order[0 .. count) (order == nullptr: 0 .. count), with only that kind's code in the
// kernel, the same calls as projectConstraint. The generic projectAllKernel carries every kind's path (shape
// matching included) in 56 registers. The four-particle kinds are held to 40 registers (12 blocks of 128 per
// SM): the 150k tearing sheet's bending projection took 37.8 us against 55.7 us at 56 registers, 45.2 at 48 and
// 46.1 at 32 (spilling) on the H100 (ncu, 2026-11-27); distance needs 32 on its own.
constexpr int kFourParticleMinBlocks = 12;
template <typename T, int Kind, int MinBlocks = 1>
__global__ void __launch_bounds__(kThreads, MinBlocks)
    projectKindKernel(pbd::BlockView<T> b, pbd::SolveContext<T> ctx, const std::int32_t* order, int count,
                      const int* live_count) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  count = liveCount(live_count, count);
  if (q >= count) return;
  const int c = order ? order[q] : q;
  if constexpr (Kind == pbd::kDistance)
    pbd::projectDistanceConstraint(b, c, ctx);
  else
    pbd::projectFourParticleConstraintOf<Kind == pbd::kBending>(b, c, ctx);
}

// Jacobi over constraints 0 .. count of a distance, bending or tet-volume block (arity A, slots A c .. A c + A - 1),
// the same calls as projectKindKernel with two differences in how the kernel moves data, none in the math:
// - the A ids of a constraint are one vector load (int2 / int4) instead of A scalar loads;
// - the corrections are staged in shared memory and the block's contiguous slot range is stored by the whole
//   block at once. Stored directly, a thread's corrections are A x 12 contiguous bytes, so each store instruction
//   of a warp touches one sector per thread and uses 4-5 of its 32 bytes (ncu on the 150k tearing sheet).
// Register caps of the staged kernels, measured with ncu on the 150k tearing sheet (H100, 2026-11-27): bending
// 29.0-30.4 us at 40 registers (12 blocks per SM), 25.3-26.0 at 48 (10), 26.4-27.1 at 63 (8), 29.3-30.6 at 76,
// 35.9-38.3 at 32 (spills); distance 18.7-21.3 us uncapped (79 registers: the staging copy), 15.2-17.4 at 40,
// 14.9-16.0 at 32 (16 blocks).
constexpr int kStagedBendingMinBlocks = 10;
constexpr int kStagedDistanceMinBlocks = 16;
template <typename T, int Kind, int MinBlocks = 1>
__global__ void __launch_bounds__(kThreads, MinBlocks)
    projectKindStagedKernel(pbd::BlockView<T> b, pbd::SolveContext<T> ctx, int count, const int* live_count) {
  count = liveCount(live_count, count);
  constexpr int A = Kind == pbd::kDistance ? 2 : 4;
  // Raw bytes: a __shared__ array may not have a constructor (Vec3 zero-initialises).
  __shared__ __align__(16) unsigned char stage_bytes[kThreads * A * sizeof(Vec3<T>)];
  Vec3<T>* stage = reinterpret_cast<Vec3<T>*>(stage_bytes);
  const int c0 = blockIdx.x * kThreads;
  const int c = c0 + int(threadIdx.x);
  if (c < count) {
    const std::int32_t slot0 = A * c0;
    auto emit = [&](std::int32_t slot, std::int32_t, const Vec3<T>& d, T scale) { stage[slot - slot0] = d * scale; };
    if constexpr (Kind == pbd::kDistance) {
      const int2 ij = reinterpret_cast<const int2*>(b.ids)[c];
      pbd::projectDistanceConstraintIds(b, c, ctx, ij.x, ij.y, emit);
    } else {
      const int4 q = reinterpret_cast<const int4*>(b.ids)[c];
      const std::int32_t id[4] = {q.x, q.y, q.z, q.w};
      pbd::projectFourParticleConstraintIds<Kind == pbd::kBending>(b, c, ctx, id, emit);
    }
  }
  __syncthreads();
  const int valid = min(kThreads, count - c0);
  const int scalars = valid * A * 3;
  T* dst = reinterpret_cast<T*>(b.slot_corr + std::size_t(A) * std::size_t(c0));
  const T* src = reinterpret_cast<const T*>(stage);
  int k0 = 0;
  if constexpr (sizeof(T) == 4) {
    // dst is 16-byte aligned: c0 is a multiple of kThreads, so A c0 slots are a multiple of 16 bytes.
    const int vec = scalars / 4;
    for (int k = int(threadIdx.x); k < vec; k += kThreads)
      reinterpret_cast<float4*>(dst)[k] = reinterpret_cast<const float4*>(src)[k];
    k0 = 4 * vec;
  }
  for (int k = k0 + int(threadIdx.x); k < scalars; k += kThreads) dst[k] = src[k];
}

// Gauss-Seidel: constraints order[0 .. count) of one colour share no movable particle, so in-place writes
// do not race.
template <typename T>
__global__ void projectColorKernel(pbd::BlockView<T> b, pbd::SolveContext<T> ctx, const std::int32_t* order,
                                   int count) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q >= count) return;
  pbd::projectConstraint(b, order[q], ctx);
}

// Distance, bending and tet-volume blocks through their specialised kernel, other kinds through the generic ones.
// Jacobi (order == nullptr): `count` sizes the grid; in a patched model it is a bucket (PbdCudaBackend::gridCount)
// and *live_count the constraint count, read on the device so that a captured frame stays valid when a patch
// changes it. A colour (order set, live_count null): its `count` constraints.
template <typename T>
void launchProjection(const pbd::BlockView<T>& b, const pbd::SolveContext<T>& ctx, const std::int32_t* order, int count,
                      const int* live_count, cudaStream_t stream) {
  const unsigned blocks = unsigned((count + kThreads - 1) / kThreads);
  if (ctx.jacobi && !order) {
    switch (b.kind) {
      case pbd::kDistance:
        projectKindStagedKernel<T, pbd::kDistance, kStagedDistanceMinBlocks>
            <<<blocks, kThreads, 0, stream>>>(b, ctx, count, live_count);
        return;
      case pbd::kBending:
        projectKindStagedKernel<T, pbd::kBending, kStagedBendingMinBlocks>
            <<<blocks, kThreads, 0, stream>>>(b, ctx, count, live_count);
        return;
      case pbd::kTetVolume:
        projectKindStagedKernel<T, pbd::kTetVolume, kFourParticleMinBlocks>
            <<<blocks, kThreads, 0, stream>>>(b, ctx, count, live_count);
        return;
      default: break;
    }
  }
  switch (b.kind) {
    case pbd::kDistance:
      projectKindKernel<T, pbd::kDistance><<<blocks, kThreads, 0, stream>>>(b, ctx, order, count, live_count);
      break;
    case pbd::kBending:
      projectKindKernel<T, pbd::kBending, kFourParticleMinBlocks>
          <<<blocks, kThreads, 0, stream>>>(b, ctx, order, count, live_count);
      break;
    case pbd::kTetVolume:
      projectKindKernel<T, pbd::kTetVolume, kFourParticleMinBlocks>
          <<<blocks, kThreads, 0, stream>>>(b, ctx, order, count, live_count);
      break;
    default:
      if (order)
        projectColorKernel<T><<<blocks, kThreads, 0, stream>>>(b, ctx, order, count);
      else
        projectAllKernel<T><<<blocks, kThreads, 0, stream>>>(b, ctx, live_count);
  }
}

// Cluster kinds (shape matching, Laplacian): kGroup lanes per constraint (kernels/pbd_group_projection.cuh).
// order == nullptr: constraints 0 .. count (Jacobi); else the colour's constraints order[0 .. count).
template <typename T>
__global__ void projectGroupKernel(pbd::BlockView<T> b, pbd::SolveContext<T> ctx, const std::int32_t* order, int count,
                                   const int* live_count) {
  const long long g = (long long)blockIdx.x * blockDim.x + threadIdx.x;
  count = liveCount(live_count, count);
  const int q = int(g / pbdgroup::kGroup);
  const bool valid = q < count;  // no early return: the whole warp takes part in the shuffles
  pbdgroup::projectGroup(b, valid ? (order ? order[q] : q) : 0, valid, ctx, int(threadIdx.x) % pbdgroup::kGroup);
}

inline unsigned groupBlocksFor(std::int64_t n) { return blocksFor(n * pbdgroup::kGroup); }

template <typename T>
__global__ void gatherKernel(int n, const int* live_n, pbd::BlockView<T> b, Vec3<T>* x) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= liveCount(live_n, n)) return;
  x[i] += gatherSum(b, i);
}

template <typename T>
__global__ void rotationKernel(pbd::BlockView<T> b, pbd::SolveContext<T> ctx, const int* live_count) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c >= liveCount(live_count, b.count)) return;
  pbd::updateClusterRotation(b, c, ctx);
}

}  // namespace

template <typename T>
void PbdProjectionKernels<T>::jacobi(cudaStream_t stream, const pbd::BlockView<T>& b, const pbd::SolveContext<T>& ctx,
                                     int count, const int* live_count) {
  if (pbdgroup::usesGroup(b.kind))
    projectGroupKernel<T><<<groupBlocksFor(count), kThreads, 0, stream>>>(b, ctx, nullptr, count, live_count);
  else
    launchProjection(b, ctx, nullptr, count, live_count, stream);
  INC_CUDA_LAUNCH("pbd project (jacobi)");
}

template <typename T>
void PbdProjectionKernels<T>::colour(cudaStream_t stream, const pbd::BlockView<T>& b, const pbd::SolveContext<T>& ctx,
                                     const std::int32_t* order, int count) {
  if (pbdgroup::usesGroup(b.kind))
    projectGroupKernel<T><<<groupBlocksFor(count), kThreads, 0, stream>>>(b, ctx, order, count, nullptr);
  else
    launchProjection(b, ctx, order, count, nullptr, stream);
  INC_CUDA_LAUNCH("pbd project (colour)");
}

template <typename T>
void PbdProjectionKernels<T>::gather(unsigned blocks, cudaStream_t stream, int n, const int* live_n,
                                     const pbd::BlockView<T>& b, Vec3<T>* x) {
  gatherKernel<T><<<blocks, kThreads, 0, stream>>>(n, live_n, b, x);
  INC_CUDA_LAUNCH("pbd gather");
}

template <typename T>
void PbdProjectionKernels<T>::attachments(unsigned blocks, cudaStream_t stream, int k, Vec3<T>* x, const T* w,
                                          const std::int32_t* ids, const Vec3<T>* from, const Vec3<T>* to,
                                          const T* compliance, Vec3<T>* lambda, bool xpbd, T dt, T t) {
  attachKernel<T><<<blocks, kThreads, 0, stream>>>(k, x, w, ids, from, to, compliance, lambda, xpbd, dt, t);
  INC_CUDA_LAUNCH("pbd attachments");
}

template <typename T>
void PbdProjectionKernels<T>::rotations(unsigned blocks, cudaStream_t stream, const pbd::BlockView<T>& b,
                                        const pbd::SolveContext<T>& ctx, const int* live_count) {
  rotationKernel<T><<<blocks, kThreads, 0, stream>>>(b, ctx, live_count);
  INC_CUDA_LAUNCH("pbd rotations");
}

template struct PbdProjectionKernels<float>;
template struct PbdProjectionKernels<double>;

}  // namespace inc::cuda
