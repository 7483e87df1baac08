// CUDA PBD/XPBD backend: device-resident state, one launch per block (Jacobi: project + gather) or per colour (Gauss-Seidel), frame captured in a CUDA graph, in-place device patching.
#include "kernels/pbd_solver_cuda.h"

#include <cub/cub.cuh>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "kernels/bulk_upload.h"
#include "kernels/cuda_check.h"
#include "kernels/graph_capture.h"
#include "kernels/pinned_staging.h"
#include "kernels/device_buffer.h"
#include "kernels/device_grow.h"
#include "kernels/pbd_device_cuda.h"
#include "kernels/pbd_frame_data.cuh"
#include "kernels/pbd_chebyshev_args.cuh"
#include "kernels/pbd_cluster_frame.cuh"
#include "kernels/pbd_grid_frame.cuh"
#include "kernels/pbd_group_projection.cuh"
#include "kernels/pbd_particle_ops.cuh"
#include "physics/pbd_block.h"
#include "physics/pbd_volume.h"
#include "physics/tearing_rebuild.h"

namespace inc::cuda {

namespace {

constexpr int kThreads = 128;
// Most blocks of a summary reduction (their partials are then reduced on the device in a fixed tree order, so the
// result is the same every run for the same counts). The grid grows with the count up to this (reduceBlocksFor):
// with a fixed 256 blocks of kThreads the residual pass over the 150k tearing sheet's ~450k constraints held 12 %
// of the H100's warps and took 19 us (ncu, 2026-11-27).
constexpr int kReduceBlocks = 1024;
inline int reduceBlocksFor(std::int64_t count) {
  return int(std::max<std::int64_t>(1, std::min<std::int64_t>(kReduceBlocks, (count + 4 * kThreads - 1) / (4 * kThreads))));
}

// The device copies of the counts a frame's kernels read (PbdCudaBackend::live_): entry 0 the particle count, entry
// 1 + b block b's constraint count. Written by one small launch before a frame whenever a patch changed them.
constexpr int kMaxLiveBlocks = 31;
struct LiveCounts {
  int v[1 + kMaxLiveBlocks];
  int k;
};
__global__ void setLiveKernel(LiveCounts c, int* live) {
  if (int(threadIdx.x) < c.k) live[threadIdx.x] = c.v[threadIdx.x];
}

inline unsigned blocksFor(std::int64_t n) { return unsigned((n + kThreads - 1) / kThreads); }

// Profile labels (local: this library does not link the host library's pbdConstraintKindName).
inline const char* kindName(PbdConstraintKind k) {
  switch (k) {
    case PbdConstraintKind::Distance: return "distance";
    case PbdConstraintKind::Bending: return "bending";
    case PbdConstraintKind::TetVolume: return "tet_volume";
    case PbdConstraintKind::Laplacian: return "laplacian";
    case PbdConstraintKind::ShapeMatching: return "shape_matching";
  }
  return "block";
}

// The count a frame kernel stops at: its argument, or once the model was patched on the device the live count in
// device memory (PbdCudaBackend::live_), so that a captured frame stays valid across patches. Unpatched models pass
// no pointer and pay no load.
__device__ __forceinline__ int liveCount(const int* live, int count) { return live ? *live : count; }

// ----------------------------------------------------------------------------------------------
// Kernels: each is one loop of the CPU backend (cpu_fallback/pbd_solver_cpu.cpp) with the same physics calls.

template <typename T>
__global__ void predictKernel(int n, const int* live_n, Vec3<T>* x, Vec3<T>* v, Vec3<T>* x_prev, const T* w, Vec3<T> g, T damp,
                              T dt, Vec3<T>* cheb_x1) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= liveCount(live_n, n)) return;
  pbd::predictParticle(x[i], v[i], x_prev[i], w[i], g, damp, dt);
  if (cheb_x1) cheb_x1[i] = x[i];  // Chebyshev: the substep's first iterate
}

template <typename T>
__global__ void kinematicKernel(int k, Vec3<T>* x, const std::int32_t* ids, const Vec3<T>* from, const Vec3<T>* to,
                                T t) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q >= k) return;
  x[ids[q]] = pbd::lerp(from[q], to[q], t);
}

template <typename T>
__global__ void gatherKinematicKernel(int k, const Vec3<T>* x, const std::int32_t* ids, Vec3<T>* from) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q < k) from[q] = x[ids[q]];
}

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
__global__ void __launch_bounds__(kThreads, MinBlocks) projectKindKernel(pbd::BlockView<T> b, pbd::SolveContext<T> ctx, const std::int32_t* order, int count, const int* live_count) {
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
__global__ void __launch_bounds__(kThreads, MinBlocks) projectKindStagedKernel(pbd::BlockView<T> b, pbd::SolveContext<T> ctx, int count, const int* live_count) {
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
__global__ void projectColorKernel(pbd::BlockView<T> b, pbd::SolveContext<T> ctx, const std::int32_t* order, int count) {
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
        projectKindStagedKernel<T, pbd::kDistance, kStagedDistanceMinBlocks><<<blocks, kThreads, 0, stream>>>(b, ctx, count, live_count);
        return;
      case pbd::kBending:
        projectKindStagedKernel<T, pbd::kBending, kStagedBendingMinBlocks><<<blocks, kThreads, 0, stream>>>(b, ctx, count, live_count);
        return;
      case pbd::kTetVolume:
        projectKindStagedKernel<T, pbd::kTetVolume, kFourParticleMinBlocks><<<blocks, kThreads, 0, stream>>>(b, ctx, count, live_count);
        return;
      default: break;
    }
  }
  switch (b.kind) {
    case pbd::kDistance: projectKindKernel<T, pbd::kDistance><<<blocks, kThreads, 0, stream>>>(b, ctx, order, count, live_count); break;
    case pbd::kBending:
      projectKindKernel<T, pbd::kBending, kFourParticleMinBlocks><<<blocks, kThreads, 0, stream>>>(b, ctx, order, count, live_count);
      break;
    case pbd::kTetVolume:
      projectKindKernel<T, pbd::kTetVolume, kFourParticleMinBlocks><<<blocks, kThreads, 0, stream>>>(b, ctx, order, count, live_count);
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

template <typename T>
__global__ void contactKernel(int n, const int* live_n, Vec3<T>* x, const T* r, const T* inset, const Vec3<T>* x_prev,
                              const T* w,
                              const pbd::PlaneCollider<T>* planes,
                              int np, const pbd::BoxCollider<T>* boxes, int nb, const pbd::CapsuleCollider<T>* tools_from,
                              const pbd::CapsuleCollider<T>* tools_to, int nt, T t0, T t, ChebyshevArgs<T> ch) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < liveCount(live_n, n))
    x[i] = endIterationAt(i, x[i], r, inset, x_prev, w, planes, np, boxes, nb, tools_from, tools_to, nt, t0, t, ch);
  chebyshevMultipliers(ch);
}

// The last Jacobi block's gather and then the iteration's contacts, per particle in one pass: a particle's contact
// reads only its own gathered position, so this is the two kernels' result (the same operations on each particle
// in the same order) without the second pass over the positions and its launch. Both contact kernels take the
// iteration's Chebyshev step (positions before their contacts, as the CPU's contact phase does, and every multiplier).
template <typename T>
__global__ void gatherContactKernel(int n, const int* live_n, pbd::BlockView<T> b, Vec3<T>* x, const T* r,
                                    const T* inset, const Vec3<T>* x_prev, const T* w,
                                    const pbd::PlaneCollider<T>* planes, int np, const pbd::BoxCollider<T>* boxes,
                                    int nb, const pbd::CapsuleCollider<T>* tools_from,
                                    const pbd::CapsuleCollider<T>* tools_to, int nt, T t0, T t, ChebyshevArgs<T> ch) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < liveCount(live_n, n))
    x[i] = endIterationAt(i, x[i] + gatherSum(b, i), r, inset, x_prev, w, planes, np, boxes, nb, tools_from, tools_to, nt, t0,
                          t, ch);
  chebyshevMultipliers(ch);
}

template <typename T>
__global__ void velocityKernel(int n, const int* live_n, const Vec3<T>* x, const Vec3<T>* x_prev, Vec3<T>* v, T inv_dt) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= liveCount(live_n, n)) return;
  v[i] = (x[i] - x_prev[i]) * inv_dt;
}

// Spheres whose radius is solved this frame: all (influence < 0) or those within influence of a tool.
template <typename T>
__global__ void volumeActiveKernel(int n, const Vec3<T>* x, const T* rest_r, const pbd::CapsuleCollider<T>* tools_to,
                                   int nt, T influence, std::uint8_t* active) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  std::uint8_t a = influence < T(0) ? 1 : 0;
  for (int k = 0; k < nt && !a; ++k)
    if (pbd::capsuleDistance(x[i], tools_to[k]) <= rest_r[i] + influence) a = 1;
  active[i] = a;
}

template <typename T>
__global__ void radiusKernel(int n, const Vec3<T>* x, const T* radii, T* radii_next, const T* rest_r,
                             const T* rest_cell, const std::int32_t* ov_off, const std::int32_t* ov_ids,
                             const Vec3<T>* samples, int sample_count, const std::uint8_t* active, T growth,
                             int bisection_steps) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const T r0 = rest_r[i];
  if (!active[i]) {
    radii_next[i] = r0;
    return;
  }
  const std::int32_t b = ov_off[i], e = ov_off[i + 1];
  radii_next[i] = pbd::radiusForCellVolume(x[i], r0, r0 * growth, rest_cell[i], x, radii, ov_ids + b, e - b, samples,
                                           sample_count, bisection_steps);
}

template <typename T>
__global__ void restRadiiKernel(int n, const int* live_n, T* radii, const T* rest_r) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= liveCount(live_n, n)) return;
  radii[i] = rest_r[i];
}

// Per-block partials of the distance residual: max and sum of squares (double), fixed tree order.
template <typename T>
__global__ void residualKernel(pbd::BlockView<T> b, const Vec3<T>* x, bool xpbd, T dt, double* part_max,
                               double* part_sum) {
  __shared__ double smax[kThreads];
  __shared__ double ssum[kThreads];
  double m = 0.0, s = 0.0;
  for (int c = blockIdx.x * blockDim.x + threadIdx.x; c < b.count; c += gridDim.x * blockDim.x) {
    const double r = double(pbd::distanceResidual(b, c, x, xpbd, dt));
    m = m > r ? m : r;
    s += r * r;
  }
  smax[threadIdx.x] = m;
  ssum[threadIdx.x] = s;
  __syncthreads();
  for (int h = blockDim.x / 2; h > 0; h /= 2) {
    if (threadIdx.x < h) {
      smax[threadIdx.x] = smax[threadIdx.x] > smax[threadIdx.x + h] ? smax[threadIdx.x] : smax[threadIdx.x + h];
      ssum[threadIdx.x] += ssum[threadIdx.x + h];
    }
    __syncthreads();
  }
  if (threadIdx.x == 0) {
    part_max[blockIdx.x] = smax[0];
    part_sum[blockIdx.x] = ssum[0];
  }
}

// Per-block partials over particles: first non-finite particle (n if none), active count, max radius ratio.
template <typename T>
__global__ void summaryKernel(int n, const Vec3<T>* x, const Vec3<T>* v, const T* r, const T* rest_r,
                              const std::uint8_t* active, double* part_bad, double* part_active,
                              double* part_ratio) {
  __shared__ long long sbad[kThreads];
  __shared__ long long sact[kThreads];
  __shared__ double srat[kThreads];
  long long bad = n, act = 0;
  double rat = 1.0;
  for (int i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x) {
    // r - r is NaN exactly when r is NaN or infinite
    if ((!isFinite(x[i]) || !isFinite(v[i]) || !(r[i] - r[i] == T(0))) && i < bad) bad = i;
    act += active[i];
    if (rest_r[i] > T(0)) {
      const double q = double(r[i] / rest_r[i]);
      rat = rat > q ? rat : q;
    }
  }
  sbad[threadIdx.x] = bad;
  sact[threadIdx.x] = act;
  srat[threadIdx.x] = rat;
  __syncthreads();
  for (int h = blockDim.x / 2; h > 0; h /= 2) {
    if (threadIdx.x < h) {
      sbad[threadIdx.x] = sbad[threadIdx.x] < sbad[threadIdx.x + h] ? sbad[threadIdx.x] : sbad[threadIdx.x + h];
      sact[threadIdx.x] += sact[threadIdx.x + h];
      srat[threadIdx.x] = srat[threadIdx.x] > srat[threadIdx.x + h] ? srat[threadIdx.x] : srat[threadIdx.x + h];
    }
    __syncthreads();
  }
  if (threadIdx.x == 0) {
    part_bad[blockIdx.x] = double(sbad[0]);  // exact: indices and counts are far below 2^53
    part_active[blockIdx.x] = double(sact[0]);
    part_ratio[blockIdx.x] = srat[0];
  }
}

// The summary's partial groups reduced on the device: the used[g] partials of group g (its reduction's grid) ->
// totals[g], one block per group in a fixed tree order. Groups 0 .. 2 nd - 1 are the distance blocks' (max, sum)
// pairs, then (min, sum, max) of summaryKernel. One small download instead of all the partials.
struct FinishPlan {
  int nd = 0;
  int used[2 * kMaxLiveBlocks + 3] = {};
};
__global__ void __launch_bounds__(kReduceBlocks) finishPartialsKernel(const double* part, FinishPlan plan, double* totals) {
  __shared__ double s[kReduceBlocks];
  const int g = blockIdx.x, t = threadIdx.x, nd = plan.nd;
  const int op = g < 2 * nd ? (g % 2 == 0 ? 2 : 0) : (g == 2 * nd ? 1 : (g == 2 * nd + 1 ? 0 : 2));  // 0 sum, 1 min, 2 max
  const double identity = op == 0 ? 0.0 : (op == 1 ? DBL_MAX : -DBL_MAX);
  s[t] = t < plan.used[g] ? part[std::size_t(g) * kReduceBlocks + t] : identity;
  __syncthreads();
  for (int h = kReduceBlocks / 2; h > 0; h /= 2) {
    if (t < h) {
      const double a = s[t], b = s[t + h];
      s[t] = op == 0 ? a + b : (op == 1 ? (a < b ? a : b) : (a > b ? a : b));
    }
    __syncthreads();
  }
  if (t == 0) totals[g] = s[0];
}

// ----------------------------------------------------------------------------------------------
// Patch kernels (PbdDevicePatch): frame inverse masses, appended particles, block incidence.

template <typename T>
__global__ void zeroKinematicKernel(int k, T* w, const std::int32_t* ids) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q >= k) return;
  w[ids[q]] = T(0);
}

// appendParticles in one launch: inverse masses of all n1 particles (the split ones changed mass), and the
// appended ones [n0, n1) start with no radius, no rotation and inactive.
template <typename T>
__global__ void appendParticlesKernel(int n0, int n1, const T* mass, const std::uint8_t* fixed, T* inv_mass, T* rest_r,
                                      T* r, T* r_next, pbd::Quat<T>* rot, std::uint8_t* active) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n1) return;
  inv_mass[i] = fixed[i] ? T(0) : T(1) / mass[i];
  if (i < n0) return;
  rest_r[i] = T(0);
  r[i] = T(0);
  r_next[i] = T(0);
  rot[i] = pbd::Quat<T>{};
  active[i] = 0;
}

__global__ void slotIotaKernel(int slots, const std::int32_t* ids, std::uint32_t* keys, std::int32_t* vals) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q >= slots) return;
  keys[q] = std::uint32_t(ids[q]);
  vals[q] = q;
}

// particle_offsets[p] = first sorted slot of particle p (p = 0 .. n): a binary search per particle.
__global__ void csrOffsetsKernel(int n, const std::uint32_t* sorted, int slots, std::int32_t* offsets) {
  const int p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p > n) return;
  offsets[p] = std::int32_t(tear::lowerBound<std::uint32_t>(sorted, slots, std::uint32_t(p)));
}

// A patched block's derived arrays in one launch (after its particle -> slot CSR): constraint offsets (count + 1),
// Jacobi scales and zeroed multipliers. Not slot_corr: every Jacobi projection writes all of its block's slots
// before the gather reads them.
template <typename T>
__global__ void commitBlockKernel(int count, int arity, const std::int32_t* ids, const std::int32_t* particle_offsets,
                                  const T* inv_mass, std::int32_t* offsets, T* scale, Vec3<T>* lambda) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c > count) return;
  offsets[c] = arity * c;
  if (c == count) return;
  const T sc = tear::jacobiScaleOf(ids, arity, c, particle_offsets, inv_mass);
  for (int k = 0; k < arity; ++k) scale[arity * c + k] = sc;
  lambda[c] = Vec3<T>();
}

inline int blockArity(PbdConstraintKind k) {
  if (k == PbdConstraintKind::Distance) return 2;
  if (k == PbdConstraintKind::Bending || k == PbdConstraintKind::TetVolume) return 4;
  return 0;
}

// Small models (the haptic case): the whole constraint loop of a frame in one thread block. Each phase is a
// block-strided loop over the same physics calls as the per-phase kernels above, separated by
// __syncthreads() (which orders this block's global-memory writes), so the result equals the multi-launch
// path bit for bit while paying one launch per frame instead of one per block, colour and iteration.
constexpr int kFusedThreads = 1024;
constexpr int kFusedJacobiMaxParticles = 256;

// Dynamic shared memory the fused kernel needs to stage n particles (rotations, positions, w, mass).
template <typename T>
std::size_t fusedStageBytes(int n) {
  return std::size_t(n) * (sizeof(pbd::Quat<T>) + sizeof(Vec3<T>) + 2 * sizeof(T));
}

extern __shared__ __align__(16) unsigned char fused_stage[];

template <typename T>
__global__ void __launch_bounds__(kFusedThreads) fusedFrameKernel(FusedFrame<T> f) {
  const int tid = threadIdx.x, nth = blockDim.x;
  // The projections are latency-bound chains of gathers (a few constraints per colour, one thread each):
  // with staging, every particle read and in-place write of the frame hits shared memory instead of
  // global memory. The arithmetic is unchanged, so the result is the same bit for bit.
  Vec3<T>* x = f.x;
  const T* w = f.w;
  pbd::SolveContext<T> ctx = f.ctx;
  if (f.staged) {
    pbd::Quat<T>* srot = reinterpret_cast<pbd::Quat<T>*>(fused_stage);
    Vec3<T>* sx = reinterpret_cast<Vec3<T>*>(srot + f.n);
    T* sw = reinterpret_cast<T*>(sx + f.n);
    T* sm = sw + f.n;
    for (int i = tid; i < f.n; i += nth) {
      sx[i] = f.x[i];
      sw[i] = f.w[i];
      sm[i] = f.ctx.mass[i];
      if (f.ctx.rotation) srot[i] = f.ctx.rotation[i];
    }
    __syncthreads();
    x = sx;
    w = sw;
    ctx.x = sx;
    ctx.w = sw;
    ctx.mass = sm;
    if (f.ctx.rotation) ctx.rotation = srot;
  }
  for (int s = 0; s < f.substeps; ++s) {
    const T t_start = T(s) / T(f.substeps), t_end = T(s + 1) / T(f.substeps);
    for (int i = tid; i < f.n; i += nth) pbd::predictParticle(x[i], f.v[i], f.x_prev[i], w[i], f.g, f.damp, f.dt);
    for (int b = 0; b < f.nblocks; ++b)
      for (int k = tid; k < f.blocks[b].multipliers; k += nth) f.blocks[b].view.lambda[k] = Vec3<T>();
    for (int k = tid; k < f.n_att; k += nth) f.att_lambda[k] = Vec3<T>();
    __syncthreads();
    for (int q = tid; q < f.n_kin; q += nth) x[f.kin_ids[q]] = pbd::lerp(f.kin_from[q], f.kin_to[q], t_end);
    __syncthreads();
    for (int it = 0; it < f.iterations; ++it) {
      for (int b = 0; b < f.nblocks; ++b) {
        const FusedBlock<T>& fb = f.blocks[b];
        if (!fb.solve || fb.view.count == 0) continue;
        const bool group = pbdgroup::usesGroup(fb.view.kind);
        const int per_pass = nth / pbdgroup::kGroup, lane = tid % pbdgroup::kGroup;
        if (ctx.jacobi) {
          if (group)  // the same trip count for every thread: all lanes of a warp reach the shuffles
            for (int base = 0; base < fb.view.count; base += per_pass)
              pbdgroup::projectGroup(fb.view, base + tid / pbdgroup::kGroup, base + tid / pbdgroup::kGroup < fb.view.count,
                                     ctx, lane);
          else
            for (int c = tid; c < fb.view.count; c += nth) pbd::projectConstraint(fb.view, c, ctx);
          __syncthreads();
          for (int i = tid; i < f.n; i += nth) x[i] += pbd::gatherCorrection(fb.view, std::int32_t(i));
          __syncthreads();
        } else {
          for (int k = 0; k < fb.colors; ++k) {
            const int c0 = fb.color_offsets[k], c1 = fb.color_offsets[k + 1];
            if (group)
              for (int base = c0; base < c1; base += per_pass) {
                const int q = base + tid / pbdgroup::kGroup;
                pbdgroup::projectGroup(fb.view, q < c1 ? fb.order[q] : 0, q < c1, ctx, lane);
              }
            else
              for (int q = c0 + tid; q < c1; q += nth) pbd::projectConstraint(fb.view, fb.order[q], ctx);
            __syncthreads();
          }
        }
      }
      for (int q = tid; q < f.n_att; q += nth) {
        const std::int32_t id = f.att_ids[q];
        pbd::projectAttachment(x[id], w[id], pbd::lerp(f.att_from[q], f.att_to[q], t_end), f.att_comp[q],
                               ctx.xpbd, f.dt, f.att_lambda[q]);
      }
      __syncthreads();
      for (int i = tid; i < f.n; i += nth)
        if (w[i] > T(0))
          x[i] = pbd::resolveContacts(x[i], f.r[i], f.inset ? f.inset[i] : T(0), f.x_prev + i, f.planes, f.np, f.boxes, f.nb, f.tools_from, f.tools_to, f.nt,
                                        t_start, t_end);
      __syncthreads();
    }
    const T inv_dt = T(1) / f.dt;
    for (int i = tid; i < f.n; i += nth) f.v[i] = (x[i] - f.x_prev[i]) * inv_dt;
    __syncthreads();
  }
  if (f.staged) {
    for (int i = tid; i < f.n; i += nth) {
      f.x[i] = x[i];
      if (f.ctx.rotation) f.ctx.rotation[i] = ctx.rotation[i];
    }
  }
}

// ----------------------------------------------------------------------------------------------

template <typename T>
struct DeviceBlock {
  PbdConstraintKind kind = PbdConstraintKind::Distance;
  bool solve = true;
  T stiffness = T(1);
  int count = 0;
  DeviceBuffer<std::int32_t> offsets, ids, particle_offsets, particle_slots, order;
  DeviceBuffer<T> rest, compliance, jacobi_scale;
  DeviceBuffer<Vec3<T>> rest_vec, lambda, slot_corr;
  DeviceBuffer<Vec3<T>> cheb1, cheb2;       // Chebyshev: multipliers one and two iterations back (sized on demand)
  std::vector<std::int32_t> color_offsets;  // host: launch ranges
  DeviceBuffer<std::int32_t> color_offsets_dev;  // the same, for the fused small-model kernel
};

// What a captured graph depends on besides stable buffer pointers; a change re-captures.
template <typename T>
struct GraphKey {
  PbdStepParams<T> p;
  std::size_t kinematic = 0, tools = 0, volume_tools = 0;
  std::size_t attached = 0;
  const void* ptrs[11] = {};  // frame-input buffers
  // Grid sizes of the particle and per-block launches (PbdCudaBackend::gridCount: buckets once the model was patched,
  // the counts themselves in the single-kernel frames, which take them as arguments).
  int n = 0;
  int counts[kMaxLiveBlocks] = {};
  bool patched = false;
  std::uint64_t topo = 0;     // PbdCudaBackend::topo_version_
};

template <typename T>
bool sameKey(const GraphKey<T>& a, const GraphKey<T>& b) {
  const PbdStepParams<T>&x = a.p, &y = b.p;
  return x.frame_dt == y.frame_dt && x.substeps == y.substeps && x.iterations == y.iterations && x.xpbd == y.xpbd &&
         x.solver == y.solver && x.jacobi_omega == y.jacobi_omega && x.gravity.x == y.gravity.x &&
         x.gravity.y == y.gravity.y && x.gravity.z == y.gravity.z && x.damping == y.damping &&
         x.rotation_iterations == y.rotation_iterations && x.volume_preservation == y.volume_preservation &&
         x.volume_influence == y.volume_influence && x.max_radius_growth == y.max_radius_growth &&
         x.volume_passes == y.volume_passes && x.bisection_steps == y.bisection_steps &&
         x.fused_max_particles == y.fused_max_particles && x.cluster_max_particles == y.cluster_max_particles &&
         x.cluster_ctas == y.cluster_ctas && x.grid_max_particles == y.grid_max_particles &&
         x.chebyshev_rho == y.chebyshev_rho &&
         a.kinematic == b.kinematic &&
         a.tools == b.tools && a.volume_tools == b.volume_tools && a.attached == b.attached && std::equal(a.ptrs, a.ptrs + 11, b.ptrs) &&
         a.n == b.n && std::equal(a.counts, a.counts + kMaxLiveBlocks, b.counts) && a.patched == b.patched &&
         a.topo == b.topo;
}

template <typename T>
class PbdCudaBackend final : public PbdBackend<T>, public PbdDevicePatch<T> {
 public:
  // A blocking stream: it orders itself after the synchronous cudaMemcpy uploads of DeviceBuffer (legacy
  // default stream), so a frame never reads an input whose DMA is still in flight.
  PbdCudaBackend() {
    INC_CUDA(cudaStreamCreate(&stream_));
    live_.resize(1 + kMaxLiveBlocks);  // one allocation for the backend's life: captured frames hold its address
  }
  ~PbdCudaBackend() override {
    destroyGraph();
    for (cudaEvent_t e : events_) cudaEventDestroy(e);
    if (stream_) cudaStreamDestroy(stream_);
  }
  PbdCudaBackend(const PbdCudaBackend&) = delete;
  PbdCudaBackend& operator=(const PbdCudaBackend&) = delete;

  BackendKind kind() const override { return BackendKind::Cuda; }

  // A new model reuses the device buffers of the last one wherever they are large enough (a cut rebuilds the
  // model every frame the blade enters new spheres: freeing and allocating ~100 buffers cost ~2 ms there), its
  // arrays travel packed in one page-locked buffer (BulkUpload: one wait instead of ~80 synchronous copies), and
  // keeps the executable graph for cudaGraphExecUpdate: the topology version makes the key stale, so the graph
  // is re-captured before it is launched again.
  void setModel(const PbdModel<T>& m) override {
    if (m.blocks.size() > std::size_t(kMaxLiveBlocks))
      throw InputError("pbd model", "blocks", "at most " + std::to_string(kMaxLiveBlocks) + " constraint blocks on CUDA");
    ++topo_version_;
    live_dirty_ = true;
    has_coloring_ = pbdModelHasColoring(m);
    patched_ = false;
    frame_count_ = 0;
    n_ = int(m.size());
    host_rest_radii_ = m.rest_radii;
    rotation_block_ = m.rotation_block;
    bulk_.add(rest_positions_, m.rest_positions);
    bulk_.add(x_, m.rest_positions);
    bulk_.zero(v_, m.size());
    bulk_.zero(x_prev_, m.size());
    bulk_.add(masses_, m.masses);
    bulk_.add(inv_mass_, m.inv_mass);
    bulk_.add(w_, m.inv_mass);
    bulk_.add(rest_radii_, m.rest_radii);
    bulk_.add(radii_, m.rest_radii);
    bulk_.add(radii_next_, m.rest_radii);
    has_inset_ = !m.contact_inset.empty();
    if (has_inset_) bulk_.add(inset_, m.contact_inset);
    std::vector<pbd::Quat<T>> ident(m.size());
    bulk_.add(rotations_, ident);
    bulk_.zero(active_, m.size());
    bulk_.add(planes_, m.planes);
    bulk_.add(boxes_, m.boxes);
    n_planes_ = int(m.planes.size());
    n_boxes_ = int(m.boxes.size());
    bulk_.add(ov_off_, m.overlap_offsets);
    bulk_.add(ov_ids_, m.overlap_ids);
    bulk_.add(rest_cell_, m.rest_cell_volume);
    bulk_.add(samples_, m.ball_samples);
    have_volume_data_ = m.rest_cell_volume.size() == m.size() && !m.ball_samples.empty() &&
                        m.overlap_offsets.size() == m.size() + 1;
    updateStaging();
    blocks_.resize(m.blocks.size());
    for (std::size_t bi = 0; bi < m.blocks.size(); ++bi) {
      const PbdConstraintBlock<T>& s = m.blocks[bi];
      DeviceBlock<T>& d = blocks_[bi];
      d.kind = s.kind;
      d.solve = s.solve;
      d.stiffness = s.stiffness;
      d.count = int(s.count());
      bulk_.add(d.offsets, s.offsets);
      bulk_.add(d.ids, s.ids);
      bulk_.add(d.particle_offsets, s.particle_offsets);
      bulk_.add(d.particle_slots, s.particle_slots);
      bulk_.add(d.order, s.coloring.order);
      d.color_offsets = s.coloring.color_offsets;
      bulk_.add(d.color_offsets_dev, s.coloring.color_offsets);
      bulk_.add(d.rest, s.rest);
      bulk_.add(d.compliance, s.compliance);
      bulk_.add(d.jacobi_scale, s.jacobi_scale);
      bulk_.add(d.rest_vec, s.rest_vec);
      bulk_.zero(d.lambda, s.multiplierCount());
      bulk_.zero(d.slot_corr, s.slotCount());
    }
    // Host copies for the cluster frame's plan, kept only for models whose particle replica can fit a CTA's shared
    // memory (the plan needs them; a large model, e.g. a tearing sheet re-set every tearing frame, skips the copy).
    cluster_meta_.clear();
    if (clusterStageBytes<T>(n_, 0) <= std::size_t(sharedOptin()))
      for (const PbdConstraintBlock<T>& b : m.blocks)
        cluster_meta_.push_back({b.offsets, b.particle_slots, b.solve, int(b.kind)});
    cluster_planned_for_ = -1;  // planned at the first Jacobi frame (planCluster)
    int reduced_blocks = 0;
    for (const DeviceBlock<T>& d : blocks_)
      if (d.kind == PbdConstraintKind::Distance && d.solve && d.count > 0) ++reduced_blocks;
    bulk_.zero(partials_, std::size_t(2 * reduced_blocks + 3) * (kReduceBlocks + 1));  // partials, then totals
    INC_CUDA(cudaDeviceSynchronize());  // no stream (this one or another) still reads the old model's buffers
    bulk_.flush(stream_);               // one wait for every copy and memset above
  }

  void setState(const PbdState<T>& s) override {
    const std::size_t n = std::size_t(n_);
    if (s.positions.size() != n || s.velocities.size() != n || s.radii.size() != n || s.rotations.size() != n)
      throw InputError("pbd state", "size", "state arrays must have one entry per particle");
    INC_CUDA(cudaStreamSynchronize(stream_));
    x_.upload(s.positions);
    v_.upload(s.velocities);
    radii_.upload(s.radii);
    rotations_.upload(s.rotations);
  }

  void getPositions(std::vector<Vec3<T>>& positions) const override {
    INC_CUDA(cudaStreamSynchronize(stream_));
    positions = x_.download();
  }

  void getState(PbdState<T>& s) const override {
    INC_CUDA(cudaStreamSynchronize(stream_));
    s.positions = x_.download();
    s.velocities = v_.download();
    s.radii = radii_.download();
    s.rotations = rotations_.download();
  }

  MemoryReport memory() const override {
    MemoryReport r;
    std::size_t b = x_.capacityBytes() + v_.capacityBytes() + x_prev_.capacityBytes() + rest_positions_.capacityBytes() +
                    masses_.capacityBytes() + inv_mass_.capacityBytes() + w_.capacityBytes() +
                    rest_radii_.capacityBytes() + radii_.capacityBytes() + radii_next_.capacityBytes() +
                    rotations_.capacityBytes() + active_.capacityBytes() + ov_off_.capacityBytes() +
                    ov_ids_.capacityBytes() + rest_cell_.capacityBytes() + samples_.capacityBytes();
    for (const DeviceBlock<T>& d : blocks_)
      b += d.offsets.capacityBytes() + d.ids.capacityBytes() + d.particle_offsets.capacityBytes() +
           d.particle_slots.capacityBytes() + d.order.capacityBytes() + d.rest.capacityBytes() +
           d.compliance.capacityBytes() + d.jacobi_scale.capacityBytes() + d.rest_vec.capacityBytes() +
           d.lambda.capacityBytes() + d.slot_corr.capacityBytes();
    r.device_bytes = b;
    r.host_bytes = host_rest_radii_.size() * sizeof(T);
    return r;
  }

  PbdFrameStats advanceFrame(const PbdStepParams<T>& p, const PbdFrameInput<T>& in) override {
    validateFrameInput(std::size_t(n_), p, in);
    direct_frame_ = false;  // also after a frame whose recording threw
    PbdFrameStats st;
    // Per-frame inputs (synchronous uploads: the previous frame has finished with these buffers).
    INC_CUDA(cudaStreamSynchronize(stream_));
    uploadFrameInput(in);
    uploadLive();

    const bool jacobi = p.solver == PbdSolverKind::Jacobi;
    if (!jacobi && patched_)
      throw InputError("pbd frame", "solver", "the model was patched on the device (no colouring): use the Jacobi solver");
    if (!jacobi && !has_coloring_)
      throw InputError("pbd frame", "solver", "the model was built without a colouring (Jacobi only): use the Jacobi solver");
    if (p.chebyshev_rho > T(0)) ensureChebyshev(p);
    if (!jacobi)
      for (const DeviceBlock<T>& d : blocks_)
        if (d.solve) st.colors += int(d.color_offsets.size()) - 1;
    st.iterations = p.substeps * p.iterations;
    // The cluster frame's plan sets kernel attributes: outside any capture, before the frame is recorded.
    if (jacobi && !patched_ && n_ <= p.cluster_max_particles) planCluster(p.cluster_ctas);
    if (jacobi && !patched_ && n_ <= p.grid_max_particles) planGrid();

    if (p.profile_stages) {
      profile_ = true;
      prof_.clear();
      recordFrame(p);
      profile_ = false;
      INC_CUDA(cudaStreamSynchronize(stream_));
      // Five stages ("constraints" includes every block, attachments and rotations), then one entry per
      // solved block, "<kind>#<block index>", so the lead can see which constraint kind costs the time.
      const char* names[] = {"predict", "constraints", "collisions", "velocities", "volume"};
      std::vector<double> ms(5 + blocks_.size(), 0.0);
      for (const ProfRecord& r : prof_) {
        float e = 0.f;
        INC_CUDA(cudaEventElapsedTime(&e, events_[r.start], events_[r.stop]));
        ms[std::size_t(r.stage)] += double(e);
      }
      for (std::size_t bi = 0; bi < blocks_.size(); ++bi) ms[1] += ms[5 + bi];
      for (int k = 0; k < 5; ++k) st.stages.push_back({names[k], ms[std::size_t(k)]});
      for (std::size_t bi = 0; bi < blocks_.size(); ++bi)
        if (blocks_[bi].solve && blocks_[bi].count > 0)
          st.stages.push_back({std::string(kindName(blocks_[bi].kind)) + "#" + std::to_string(bi),
                               ms[5 + bi]});
    } else {
      ensureEvents(2);
      INC_CUDA(cudaEventRecord(events_[0], stream_));
      if (p.use_graph) {
        GraphKey<T> key;
        key.p = p;
        key.kinematic = in.kinematic_ids.size();
        key.tools = in.tools_from.size();
        key.volume_tools = std::size_t(in.volumeToolCount());
        key.attached = in.attach_ids.size();
        const void* ptrs[11] = {kin_ids_.data(),    kin_from_.data(),  kin_to_.data(),      tools_from_.data(),
                                tools_to_.data(),   w_.data(),         att_ids_.data(),     att_from_.data(),
                                att_to_.data(),     att_comp_.data(),  att_lambda_.data()};
        std::copy(ptrs, ptrs + 11, key.ptrs);
        const bool exact = singleKernelFrame(p);
        key.n = exact ? n_ : gridCount(n_);
        for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
          const int c = blocks_[bi].count;
          key.counts[bi] = exact ? c : gridCount(c);
        }
        key.patched = patched_;
        key.topo = topo_version_;
        const bool stale = !graph_exec_ || !sameKey(key, graph_key_);
        // Right after a new model (a cut sets one every frame the blade enters new spheres) the frame is launched
        // directly: capturing and updating a graph costs more host time than it saves for one launch. The graph
        // is captured once the model has stayed the same for a frame. A device patch (a tearing frame) changes
        // only counts, which the kernels read from live_: the graph stays valid until a grid bucket changes.
        // (Measured 2026-11-27 on the 150k tearing sheet: capture + update every tearing frame made the solve's
        // host time 0.05-0.2 ms longer than direct launches.)
        const bool direct = stale && key.topo != last_direct_topo_;
        if (direct) last_direct_topo_ = key.topo;
        if (direct) {
          recordDirectFrame(p);
        } else if (stale) {
          // After a patch the frame usually differs only in counts and pointers: updated in place.
          captureGraph(stream_, graph_exec_, [&] { recordFrame(p); });
          graph_key_ = key;
        }
        if (!direct) INC_CUDA(cudaGraphLaunch(graph_exec_, stream_));
      } else {
        recordDirectFrame(p);
      }
      INC_CUDA(cudaEventRecord(events_[1], stream_));
      if (summaryDue()) {
        INC_CUDA(cudaEventSynchronize(events_[1]));
        float e = 0.f;
        INC_CUDA(cudaEventElapsedTime(&e, events_[0], events_[1]));
        st.stages.push_back({"frame", double(e)});
      }
    }
    st.path = last_path_;
    if (cluster_split_.profile && std::string(last_path_) == "cluster") printClusterProfile();
    if (summaryDue() || p.profile_stages) summarize(p, st);
    ++frame_count_;
    return st;
  }

  // ---------------------------------------------------------------------------------------------
  // PbdDevicePatch

  PbdDeviceParticles<T> deviceParticles() override {
    PbdDeviceParticles<T> d;
    d.n = n_;
    d.capacity = std::min({capacityOf(rest_positions_), capacityOf(x_), capacityOf(v_), capacityOf(masses_),
                           capacityOf(inv_mass_), capacityOf(w_), capacityOf(x_prev_), capacityOf(rest_radii_),
                           capacityOf(radii_), capacityOf(radii_next_), capacityOf(rotations_), capacityOf(active_)});
    d.rest = rest_positions_.data();
    d.x = x_.data();
    d.v = v_.data();
    d.mass = masses_.data();
    d.inv_mass = inv_mass_.data();
    return d;
  }

  void reserveParticles(std::size_t particles) override {
    const std::size_t keep = std::size_t(n_);
    bool grew = false;
    grew |= growKeep(rest_positions_, particles, keep);
    grew |= growKeep(x_, particles, keep);
    grew |= growKeep(v_, particles, keep);
    grew |= growKeep(x_prev_, particles, keep);
    grew |= growKeep(masses_, particles, keep);
    grew |= growKeep(inv_mass_, particles, keep);
    grew |= growKeep(w_, particles, keep);
    grew |= growKeep(rest_radii_, particles, keep);
    grew |= growKeep(radii_, particles, keep);
    grew |= growKeep(radii_next_, particles, keep);
    grew |= growKeep(rotations_, particles, keep);
    grew |= growKeep(active_, particles, keep);
    if (grew) ++topo_version_;
  }

  void appendParticles(int n_new, const std::uint8_t* fixed_dev) override {
    if (has_inset_) throw InputError("pbd patch", "contact_inset", "a model with contact insets cannot gain particles");
    if (n_new < n_) throw InputError("pbd patch", "particles", "appendParticles cannot remove particles");
    if (std::size_t(n_new) > deviceParticles().capacity)
      throw InputError("pbd patch", "particles", "call reserveParticles first (" + std::to_string(n_new) + " particles)");
    if (have_volume_data_ && n_new > n_)
      throw InputError("pbd patch", "volume", "models with volume-preservation data cannot grow on the device");
    const std::size_t m = std::size_t(n_new);
    for (auto* b : {&rest_positions_, &x_, &v_, &x_prev_}) b->resize(m);
    for (auto* b : {&masses_, &inv_mass_, &w_, &rest_radii_, &radii_, &radii_next_}) b->resize(m);
    rotations_.resize(m);
    active_.resize(m);
    if (n_new > 0) {
      appendParticlesKernel<T><<<blocksFor(n_new), kThreads, 0, stream_>>>(
          n_, n_new, masses_.data(), fixed_dev, inv_mass_.data(), rest_radii_.data(), radii_.data(), radii_next_.data(),
          rotations_.data(), active_.data());
      INC_CUDA_LAUNCH("pbd patch particles");
    }
    host_rest_radii_.resize(m, T(0));
    n_ = n_new;
    updateStaging();
    live_dirty_ = true;  // the frame's kernels read the count from live_ (no re-capture unless its bucket changes)
  }

  PbdDeviceBlock<T> reserveBlock(int block, std::size_t constraints) override {
    DeviceBlock<T>& d = patchBlock(block);
    const int a = blockArity(d.kind);
    const std::size_t c = std::size_t(d.count);
    bool grew = false;
    grew |= growKeep(d.ids, std::size_t(a) * constraints, std::size_t(a) * c);
    grew |= growKeep(d.rest, constraints, c);
    grew |= growKeep(d.compliance, constraints, c);
    if (grew) ++topo_version_;
    PbdDeviceBlock<T> r;
    r.arity = a;
    r.capacity = std::min({capacityOf(d.ids) / std::size_t(a), capacityOf(d.rest), capacityOf(d.compliance)});
    r.ids = d.ids.data();
    r.rest = d.rest.data();
    r.compliance = d.compliance.data();
    return r;
  }

  void commitBlock(int block, int count) override { commit(block, count, false); }

  PbdDeviceIncidence reserveIncidence(int block, std::size_t constraints) override {
    DeviceBlock<T>& d = patchBlock(block);
    const std::size_t slots = std::size_t(blockArity(d.kind)) * constraints;
    // No content to keep: the caller rewrites both arrays before commitBlockIncidence.
    if (growKeep(d.particle_slots, std::max<std::size_t>(slots, 1), 0) |
        growKeep(d.particle_offsets, std::size_t(n_) + 1, 0))
      ++topo_version_;
    PbdDeviceIncidence r;
    r.slot_capacity = capacityOf(d.particle_slots);
    r.particle_offsets = d.particle_offsets.data();
    r.particle_slots = d.particle_slots.data();
    return r;
  }

  void commitBlockIncidence(int block, int count) override { commit(block, count, true); }

  void setSummaryEvery(int k) override {
    if (k < 1) throw InputError("pbd patch", "summary_every", "must be >= 1");
    summary_every_ = k;
  }

  PbdConstraintBlock<T> downloadBlock(int block) const override {
    if (block < 0 || std::size_t(block) >= blocks_.size()) throw InputError("pbd patch", "block", "out of range");
    INC_CUDA(cudaStreamSynchronize(stream_));
    const DeviceBlock<T>& d = blocks_[std::size_t(block)];
    PbdConstraintBlock<T> b;
    b.kind = d.kind;
    b.solve = d.solve;
    b.stiffness = d.stiffness;
    b.offsets = d.offsets.download();
    b.ids = d.ids.download();
    b.rest = d.rest.download();
    b.rest_vec = d.rest_vec.download();
    b.compliance = d.compliance.download();
    b.particle_offsets = d.particle_offsets.download();
    b.particle_slots = d.particle_slots.download();
    b.jacobi_scale = d.jacobi_scale.download();
    return b;
  }

  std::vector<T> downloadInverseMasses() const override {
    INC_CUDA(cudaStreamSynchronize(stream_));
    return inv_mass_.download();
  }

  void setBlockFromHost(int block, const std::vector<std::int32_t>& ids, const std::vector<T>& rest,
                        const std::vector<T>& compliance) override {
    const int a = blockArity(patchBlock(block).kind);
    if (rest.size() != compliance.size() || ids.size() != std::size_t(a) * rest.size())
      throw InputError("pbd patch", "block", "ids, rest and compliance sizes do not match the block's arity");
    for (std::int32_t p : ids)
      if (p < 0 || p >= n_) throw InputError("pbd patch", "ids", "particle index out of range");
    const PbdDeviceBlock<T> r = reserveBlock(block, rest.size());
    INC_CUDA(cudaStreamSynchronize(stream_));
    if (!ids.empty()) {
      INC_CUDA(cudaMemcpy(r.ids, ids.data(), ids.size() * sizeof(std::int32_t), cudaMemcpyHostToDevice));
      INC_CUDA(cudaMemcpy(r.rest, rest.data(), rest.size() * sizeof(T), cudaMemcpyHostToDevice));
      INC_CUDA(cudaMemcpy(r.compliance, compliance.data(), compliance.size() * sizeof(T), cudaMemcpyHostToDevice));
    }
    commitBlock(block, int(rest.size()));
  }

  void appendParticlesFromHost(const std::vector<Vec3<T>>& rest, const std::vector<Vec3<T>>& x,
                               const std::vector<Vec3<T>>& v, const std::vector<T>& mass,
                               const std::vector<std::uint8_t>& fixed) override {
    const std::size_t m = rest.size();
    if (has_inset_) throw InputError("pbd patch", "contact_inset", "a model with contact insets cannot gain particles");
    if (x.size() != m || v.size() != m || mass.size() != m || fixed.size() != m || m < std::size_t(n_))
      throw InputError("pbd patch", "particles", "whole arrays of one size >= the particle count expected");
    for (T mm : mass)
      if (!(mm > T(0))) throw InputError("pbd patch", "mass", "must be > 0");
    reserveParticles(m);
    INC_CUDA(cudaStreamSynchronize(stream_));
    if (m) {
      INC_CUDA(cudaMemcpy(rest_positions_.data(), rest.data(), m * sizeof(Vec3<T>), cudaMemcpyHostToDevice));
      INC_CUDA(cudaMemcpy(x_.data(), x.data(), m * sizeof(Vec3<T>), cudaMemcpyHostToDevice));
      INC_CUDA(cudaMemcpy(v_.data(), v.data(), m * sizeof(Vec3<T>), cudaMemcpyHostToDevice));
      INC_CUDA(cudaMemcpy(masses_.data(), mass.data(), m * sizeof(T), cudaMemcpyHostToDevice));
    }
    fixed_scratch_.upload(fixed);
    appendParticles(int(m), fixed_scratch_.data());
    INC_CUDA(cudaStreamSynchronize(stream_));  // fixed_scratch_ may be overwritten by the next call
  }

 private:
  // commitBlock (caller_csr false: the particle -> slot CSR by a device radix sort) and commitBlockIncidence
  // (caller_csr true: the caller wrote it into the reserveIncidence buffers).
  void commit(int block, int count, bool caller_csr) {
    DeviceBlock<T>& d = patchBlock(block);
    const int a = blockArity(d.kind);
    if (count < 0 || std::size_t(count) > std::min(capacityOf(d.ids) / std::size_t(a), capacityOf(d.rest)) ||
        std::size_t(count) > capacityOf(d.compliance))
      throw InputError("pbd patch", "count", "call reserveBlock first (" + std::to_string(count) + " constraints)");
    const std::size_t cnt = std::size_t(count), slots = std::size_t(a) * cnt;
    // The caller's CSR must not be reallocated here (growKeep with nothing kept would drop it).
    if (caller_csr && (slots > capacityOf(d.particle_slots) || std::size_t(n_) + 1 > capacityOf(d.particle_offsets)))
      throw InputError("pbd patch", "incidence", "call reserveIncidence after appendParticles (" +
                                                     std::to_string(count) + " constraints)");
    d.ids.resize(slots);
    d.rest.resize(cnt);
    d.compliance.resize(cnt);
    // Derived arrays: no content to keep, so growing them needs no copy (and no synchronisation beyond the
    // one inside the allocation of a larger buffer, which happens only when the block outgrows its capacity).
    if (growKeep(d.offsets, cnt + 1, 0) | growKeep(d.jacobi_scale, slots, 0) | growKeep(d.particle_slots, slots, 0) |
        growKeep(d.lambda, cnt, 0) | growKeep(d.slot_corr, slots, 0) |
        growKeep(d.particle_offsets, std::size_t(n_) + 1, 0))
      ++topo_version_;
    d.offsets.resize(cnt + 1);
    d.jacobi_scale.resize(slots);
    d.particle_slots.resize(slots);
    d.lambda.resize(cnt);
    d.slot_corr.resize(slots);
    d.particle_offsets.resize(std::size_t(n_) + 1);
    d.count = count;
    if (!caller_csr) sortIncidence(d, slots);
    commitBlockKernel<T><<<blocksFor(count + 1), kThreads, 0, stream_>>>(count, a, d.ids.data(), d.particle_offsets.data(),
                                                                         inv_mass_.data(), d.offsets.data(),
                                                                         d.jacobi_scale.data(), d.lambda.data());
    INC_CUDA_LAUNCH("pbd patch block");
    d.order.resize(0);
    d.color_offsets.assign(1, 0);
    // The summary's reduction partials: room for every block (a block that was empty at setModel may not be).
    const std::size_t need = std::size_t(2 * blocks_.size() + 3) * (kReduceBlocks + 1);
    if (partials_.size() < need) partials_.resize(need);
    patched_ = true;
    live_dirty_ = true;  // as appendParticles: counts travel through live_
  }

  // particle -> slot CSR: slots sorted by particle with a stable radix sort over the index bits (slots stay
  // ascending per particle: the order finalizePbdModel's counting sort gives), offsets by binary search.
  void sortIncidence(DeviceBlock<T>& d, std::size_t slots) {
    sort_keys_.resize(std::max<std::size_t>(slots, 1));
    sort_keys_out_.resize(std::max<std::size_t>(slots, 1));
    sort_vals_.resize(std::max<std::size_t>(slots, 1));
    if (slots > 0) {
      slotIotaKernel<<<blocksFor(std::int64_t(slots)), kThreads, 0, stream_>>>(int(slots), d.ids.data(), sort_keys_.data(),
                                                                               sort_vals_.data());
      INC_CUDA_LAUNCH("pbd patch slot keys");
      const int end_bit = tear::indexBits(n_);
      std::size_t bytes = 0;
      INC_CUDA(cub::DeviceRadixSort::SortPairs(nullptr, bytes, sort_keys_.data(), sort_keys_out_.data(), sort_vals_.data(),
                                               d.particle_slots.data(), int(slots), 0, end_bit, stream_));
      cub_temp_.resize(std::max<std::size_t>(bytes, 1));
      INC_CUDA(cub::DeviceRadixSort::SortPairs(cub_temp_.data(), bytes, sort_keys_.data(), sort_keys_out_.data(),
                                               sort_vals_.data(), d.particle_slots.data(), int(slots), 0, end_bit,
                                               stream_));
    }
    csrOffsetsKernel<<<blocksFor(n_ + 1), kThreads, 0, stream_>>>(n_, sort_keys_out_.data(), int(slots),
                                                                  d.particle_offsets.data());
    INC_CUDA_LAUNCH("pbd patch particle offsets");
  }

  struct ProfRecord {
    int stage;
    std::size_t start, stop;
  };

  void ensureEvents(std::size_t k) {
    while (events_.size() < k) {
      cudaEvent_t e;
      INC_CUDA(cudaEventCreate(&e));
      events_.push_back(e);
    }
  }
  // Profiling only: event pairs around each stage launch group (summed per stage after the frame).
  std::size_t stageBegin() {
    if (!profile_) return 0;
    const std::size_t k = 2 + 2 * prof_.size();
    ensureEvents(k + 2);
    INC_CUDA(cudaEventRecord(events_[k], stream_));
    return k;
  }
  void stageEnd(int stage, std::size_t k) {
    if (!profile_) return;
    INC_CUDA(cudaEventRecord(events_[k + 1], stream_));
    prof_.push_back({stage, k, k + 1});
  }

  bool summaryDue() const { return frame_count_ % std::uint64_t(summary_every_) == 0; }

  DeviceBlock<T>& patchBlock(int block) {
    if (block < 0 || std::size_t(block) >= blocks_.size()) throw InputError("pbd patch", "block", "out of range");
    DeviceBlock<T>& d = blocks_[std::size_t(block)];
    if (blockArity(d.kind) == 0)
      throw InputError("pbd patch", "block", "only distance, bending and tet-volume blocks can be patched");
    return d;
  }

  // The device's per-block shared-memory limit (opt-in).
  static int sharedOptin() {
    int dev = 0, optin = 0;
    INC_CUDA(cudaGetDevice(&dev));
    INC_CUDA(cudaDeviceGetAttribute(&optin, cudaDevAttrMaxSharedMemoryPerBlockOptin, dev));
    return optin;
  }

  // The thread-block cluster frame (kernels/pbd_cluster_frame.cuh): how many CTAs, which constraints and slots
  // each projects, which particles each owns. Decided per model (host offsets at hand); usable when the device
  // launches clusters and every CTA's replica fits its shared memory. Attributes are set here, outside captures.
  void planCluster(int forced_ctas) {
    if (cluster_planned_for_ == forced_ctas) return;
    cluster_planned_for_ = forced_ctas;
    cluster_ok_ = false;
    if (n_ == 0 || cluster_meta_.empty() || cluster_meta_.size() > std::size_t(kMaxFusedBlocks) ||
        forced_ctas > kMaxClusterCtas)
      return;
    int dev = 0, major = 0;
    INC_CUDA(cudaGetDevice(&dev));
    INC_CUDA(cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, dev));
    if (major < 9) return;  // clusters and distributed shared memory: Hopper (sm_90) and newer
    cudaFuncAttributes fa{};
    INC_CUDA(cudaFuncGetAttributes(&fa, clusterFrameKernel<T>));
    const int dyn_max = sharedOptin() - int(fa.sharedSizeBytes);  // static shared memory counts against the limit
    // Enough CTAs that every cluster constraint gets its lanes and every scalar constraint its thread in one
    // pass (fewer CTAs: cheaper barriers), capped at the largest cluster the hardware allows.
    const int groups_per_cta = kClusterThreads / pbdgroup::kGroup;
    int want = (n_ + kClusterThreads - 1) / kClusterThreads;
    for (const ClusterBlockMeta& b : cluster_meta_) {
      const int c = int(b.offsets.size()) - 1;
      if (!b.solve || c <= 0) continue;
      const bool group = pbdgroup::usesGroup(b.kind);
      want = std::max(want, group ? (c + groups_per_cta - 1) / groups_per_cta : (c + kClusterThreads - 1) / kClusterThreads);
    }
    int ctas = forced_ctas > 0 ? forced_ctas : std::min(want, kMaxClusterCtas);
    ClusterSplit sp;
    for (; ctas >= 1; --ctas) {
      sp = ClusterSplit{};
      sp.ctas = ctas;
      sp.chunk = (n_ + ctas - 1) / ctas;
      for (std::size_t bi = 0; bi < cluster_meta_.size(); ++bi) {
        const ClusterBlockMeta& b = cluster_meta_[bi];
        const std::int64_t c = std::int64_t(b.offsets.size()) - 1;
        for (int r = 0; r <= ctas; ++r) {
          sp.c_split[bi][r] = int(c * r / ctas);
          sp.s_split[bi][r] = c > 0 ? b.offsets[std::size_t(sp.c_split[bi][r])] : 0;
        }
        if (b.solve)
          for (int r = 0; r < ctas; ++r) sp.max_share = std::max(sp.max_share, sp.s_split[bi][r + 1] - sp.s_split[bi][r]);
      }
      const std::size_t bytes = clusterStageBytes<T>(n_, sp.max_share);
      if (bytes > std::size_t(dyn_max)) break;  // fewer CTAs never shrink the replica
      INC_CUDA(cudaFuncSetAttribute(clusterFrameKernel<T>, cudaFuncAttributeMaxDynamicSharedMemorySize, dyn_max));
      INC_CUDA(cudaFuncSetAttribute(clusterFrameKernel<T>, cudaFuncAttributeNonPortableClusterSizeAllowed, 1));
      ClusterLaunch launch(ctas, bytes, nullptr);
      int clusters = 0;
      if (cudaOccupancyMaxActiveClusters(&clusters, clusterFrameKernel<T>, &launch.cfg) != cudaSuccess) {
        (void)cudaGetLastError();  // not sticky: this size cannot be launched
        clusters = 0;
      }
      if (clusters < 1) {
        if (forced_ctas > 0) return;  // the forced size cannot run here: per-launch path
        continue;
      }
      // Each particle-slot entry's home: the CTA that projects its constraint and its place in that CTA's
      // slot buffer.
      cluster_home_.resize(cluster_meta_.size());
      for (std::size_t bi = 0; bi < cluster_meta_.size(); ++bi) {
        const ClusterBlockMeta& b = cluster_meta_[bi];
        std::vector<std::int32_t> home(b.particle_slots.size());
        for (std::size_t k = 0; k < home.size(); ++k) {
          const std::int32_t slot = b.particle_slots[k];
          int r = 0;
          while (r + 1 < ctas && sp.s_split[bi][r + 1] <= slot) ++r;
          home[k] = std::int32_t((std::uint32_t(r) << 24) | std::uint32_t(slot - sp.s_split[bi][r]));
        }
        cluster_home_[bi].upload(home);
        sp.slot_home[bi] = cluster_home_[bi].data();
      }
      if (std::getenv("INCISION_PBD_CLUSTER_PROFILE")) {
        cluster_profile_.resize(std::size_t(ctas) * kClusterProfileSlots);
        sp.profile = cluster_profile_.data();
      }
      cluster_split_ = sp;
      cluster_bytes_ = bytes;
      cluster_ok_ = true;
      return;
    }
  }

  // The grid frame's resident-grid limit (blocks of kGridFrameThreads that the device holds at once), asked once per
  // backend outside any capture; 0 where the device has no cooperative launch.
  void planGrid() {
    if (grid_cap_ >= 0) return;
    int dev = 0, coop = 0, sms = 0, per_sm = 0;
    INC_CUDA(cudaGetDevice(&dev));
    INC_CUDA(cudaDeviceGetAttribute(&coop, cudaDevAttrCooperativeLaunch, dev));
    INC_CUDA(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev));
    INC_CUDA(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, gridFrameKernel<T>, kGridFrameThreads, 0));
    grid_cap_ = coop ? per_sm * sms : 0;
  }

  // One cooperative launch of the whole frame: as many blocks as the widest phase wants (a cluster constraint's
  // lanes, a scalar constraint's thread, a particle's, a multiplier's), at most the resident grid.
  void launchGridFrame(const PbdStepParams<T>& p, const FusedFrame<T>& f) {
    GridFrame<T> g;
    g.f = f;
    std::int64_t want = std::max<std::int64_t>({n_, n_att_, n_kin_});
    for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
      const DeviceBlock<T>& d = blocks_[bi];
      if (!d.solve || d.count == 0) continue;
      g.last_solved = int(bi);
      const bool group = pbdgroup::usesGroup(int(d.kind));
      want = std::max<std::int64_t>(want, group ? std::int64_t(d.count) * pbdgroup::kGroup : d.count);
    }
    if (p.chebyshev_rho > T(0)) {
      g.ch = chebyshevArgs();
      g.cheb_weights = cheb_weights_.data();
      g.cheb_rho = p.chebyshev_rho;
      want = std::max<std::int64_t>(want, g.ch.total);
    }
    const std::int64_t blocks = std::min<std::int64_t>(grid_cap_, (want + kGridFrameThreads - 1) / kGridFrameThreads);
    void* args[] = {&g};
    INC_CUDA(cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(gridFrameKernel<T>), dim3(unsigned(std::max<std::int64_t>(1, blocks))),
                                         dim3(kGridFrameThreads), args, 0, stream_));
    INC_CUDA_LAUNCH("pbd grid frame");
  }

  // Diagnostics (INCISION_PBD_CLUSTER_PROFILE set): microseconds per phase kind of the last cluster frame, as
  // CTA 0 and the slowest CTA saw them, on stderr.
  void printClusterProfile() {
    INC_CUDA(cudaStreamSynchronize(stream_));
    const std::vector<long long> c = cluster_profile_.download();
    int dev = 0, khz = 0;
    INC_CUDA(cudaGetDevice(&dev));
    INC_CUDA(cudaDeviceGetAttribute(&khz, cudaDevAttrClockRate, dev));
    const char* what[4] = {"project", "sync", "gather", "sync"};
    std::fprintf(stderr, "cluster profile (%d CTAs, us: cta0/max):", cluster_split_.ctas);
    for (int k = 0; k < kClusterProfileSlots; ++k) {
      long long mx = 0;
      for (int r = 0; r < cluster_split_.ctas; ++r) mx = std::max(mx, c[std::size_t(r * kClusterProfileSlots + k)]);
      if (mx == 0) continue;
      if (k == 0)
        std::fprintf(stderr, " start");
      else
        std::fprintf(stderr, " b%d.%s", (k - 1) / 4, what[(k - 1) % 4]);
      std::fprintf(stderr, "=%.1f/%.1f", 1e3 * double(c[std::size_t(k)]) / khz, 1e3 * double(mx) / khz);
    }
    std::fprintf(stderr, "\n");
  }

  // Shared-memory staging of the fused kernel: used when the model fits this device's per-block opt-in limit
  // (float: up to ~6,000 particles on an H100); the attribute is set here, outside any graph capture.
  void updateStaging() {
    const int optin = sharedOptin();
    stage_bytes_ = fusedStageBytes<T>(n_);
    staged_ = n_ > 0 && stage_bytes_ <= std::size_t(optin);
    // The attribute belongs to the kernel, not to this backend: set it to the device limit so that a second
    // live backend with a smaller model cannot lower it below what this one launches with.
    if (staged_) INC_CUDA(cudaFuncSetAttribute(fusedFrameKernel<T>, cudaFuncAttributeMaxDynamicSharedMemorySize, optin));
  }

  void destroyGraph() {
    if (graph_exec_) cudaGraphExecDestroy(graph_exec_);
    graph_exec_ = nullptr;
  }

  void uploadFrameInput(const PbdFrameInput<T>& in) {
    // Inverse masses of this frame: kinematic particles get w = 0 (a device copy and a scatter of zeros on the
    // stream, after the synchronous id upload; no per-particle host array crosses the bus).
    // A grasp holds the same particles frame after frame: their ids cross the bus once.
    if (in.kinematic_ids != kin_ids_host_) {
      kin_ids_.upload(in.kinematic_ids);
      kin_ids_host_ = in.kinematic_ids;
    }
    if (n_ > 0) INC_CUDA(cudaMemcpyAsync(w_.data(), inv_mass_.data(), std::size_t(n_) * sizeof(T), cudaMemcpyDeviceToDevice, stream_));
    if (!in.kinematic_ids.empty()) {
      zeroKinematicKernel<T><<<blocksFor(std::int64_t(in.kinematic_ids.size())), kThreads, 0, stream_>>>(
          int(in.kinematic_ids.size()), w_.data(), kin_ids_.data());
      INC_CUDA_LAUNCH("pbd kinematic w");
    }
    if (in.kinematic_from_positions) {
      // The start positions gathered on the device (the previous frame's work is ordered before this on stream_).
      kin_from_.resize(in.kinematic_ids.size());
      if (!in.kinematic_ids.empty()) {
        gatherKinematicKernel<T><<<blocksFor(std::int64_t(in.kinematic_ids.size())), kThreads, 0, stream_>>>(
            int(in.kinematic_ids.size()), x_.data(), kin_ids_.data(), kin_from_.data());
        INC_CUDA_LAUNCH("pbd kinematic start positions");
      }
    } else {
      kin_from_.upload(in.kinematic_from);
    }
    kin_to_.resize(in.kinematic_to.size());  // the stream is idle (advanceFrame): the staging may be rewritten
    kin_to_staging_.upload(kin_to_.data(), in.kinematic_to.data(), in.kinematic_to.size(), stream_);
    tools_from_.upload(in.tools_from);
    tools_to_.upload(in.tools_to);
    att_ids_.upload(in.attach_ids);
    att_from_.upload(in.attach_from);
    att_to_.upload(in.attach_to);
    att_comp_.upload(in.attach_compliance);
    att_lambda_.resize(in.attach_ids.size());
    n_att_ = int(in.attach_ids.size());
    n_kin_ = int(in.kinematic_ids.size());
    n_tools_ = int(in.tools_from.size());
    n_volume_tools_ = in.volumeToolCount();
  }

  // Chebyshev iterates sized for the model and this frame's attachments; a reallocation bumps topo_version_ (the
  // captured frame holds the pointers).
  void ensureChebyshev(const PbdStepParams<T>& p) {
    if (patched_)
      throw InputError("pbd frame", "chebyshev_rho", "not supported on a model patched on the device (tearing): use 0");
    if (int(blocks_.size()) + 1 > kMaxChebyshevLists)
      throw InputError("pbd frame", "chebyshev_rho", "supported for up to " + std::to_string(kMaxChebyshevLists - 1) +
                                                         " constraint blocks, the model has " + std::to_string(blocks_.size()));
    bool moved = false;
    const auto fit = [&](DeviceBuffer<Vec3<T>>& b, std::size_t n) {
      const void* before = b.data();
      b.resize(n);
      moved |= b.data() != before;
    };
    fit(cheb_x1_, std::size_t(n_));
    fit(cheb_x2_, std::size_t(n_));
    for (DeviceBlock<T>& d : blocks_) {
      fit(d.cheb1, d.lambda.size());
      fit(d.cheb2, d.lambda.size());
    }
    fit(cheb_a1_, std::size_t(n_att_));
    fit(cheb_a2_, std::size_t(n_att_));
    // The grid frame reads each iteration's weight from the device: the host's recursion, whose bits the per-block
    // launches pass as arguments (device code may contract its multiply-add differently).
    std::vector<T> weights(std::size_t(p.iterations));
    T wk = T(1);
    for (int it = 0; it < p.iterations; ++it) {
      pbd::chebyshevIteration(it, p.iterations, p.chebyshev_rho, wk);
      weights[std::size_t(it)] = wk;
    }
    if (weights != cheb_weights_host_) {
      const void* before = cheb_weights_.data();
      cheb_weights_.upload(weights);
      moved |= cheb_weights_.data() != before;
      cheb_weights_host_ = weights;
    }
    if (moved) ++topo_version_;
  }

  // The frame's Chebyshev views: positions, then the solved blocks' multipliers and the attachments' as flat lists.
  ChebyshevArgs<T> chebyshevArgs() {
    ChebyshevArgs<T> a;
    a.x1 = cheb_x1_.data();
    a.x2 = cheb_x2_.data();
    const auto add = [&](Vec3<T>* lambda, Vec3<T>* l1, Vec3<T>* l2, std::size_t count) {
      if (count == 0) return;
      a.lambda[a.lists] = lambda;
      a.l1[a.lists] = l1;
      a.l2[a.lists] = l2;
      a.total += int(count);
      a.end[a.lists++] = a.total;
    };
    for (DeviceBlock<T>& d : blocks_)
      if (d.solve) add(d.lambda.data(), d.cheb1.data(), d.cheb2.data(), d.lambda.size());
    add(att_lambda_.data(), cheb_a1_.data(), cheb_a2_.data(), std::size_t(n_att_));
    return a;
  }

  pbd::BlockView<T> view(DeviceBlock<T>& d) {
    pbd::BlockView<T> b;
    b.kind = int(d.kind);
    b.count = d.count;
    b.stiffness = d.stiffness;
    b.offsets = d.offsets.data();
    b.ids = d.ids.data();
    b.rest = d.rest.data();
    b.rest_vec = d.rest_vec.data();
    b.compliance = d.compliance.data();
    b.jacobi_scale = d.jacobi_scale.data();
    b.particle_offsets = d.particle_offsets.data();
    b.particle_slots = d.particle_slots.data();
    b.lambda = d.lambda.data();
    b.slot_corr = d.slot_corr.data();
    return b;
  }

  // Writes live_ when a patch or a new model changed the counts (one launch, ordered before the frame on stream_).
  void uploadLive() {
    if (!live_dirty_) return;
    LiveCounts c{};
    c.k = 1 + int(blocks_.size());
    c.v[0] = n_;
    for (std::size_t bi = 0; bi < blocks_.size(); ++bi) c.v[1 + bi] = blocks_[bi].count;
    setLiveKernel<<<1, 1 + kMaxLiveBlocks, 0, stream_>>>(c, live_.data());
    INC_CUDA_LAUNCH("pbd live counts");
    live_dirty_ = false;
  }

  // Grid size of a launch over `count` particles or constraints: the count itself until the model is patched on the
  // device, then a bucket (a multiple of max(2048, 1/32 of the next power of two)), so that a tearing frame's few
  // hundred new particles and constraints keep the captured graph: its kernels stop at the live count, and it is
  // re-captured when the count crosses into the next bucket (about every 3 % of growth). The bucket costs at most
  // 1/32 more (empty) blocks.
  int gridCount(int count) const {
    if (!patched_ || count <= 0) return count;
    int g = 2048;
    while (g < count / 32) g *= 2;
    return (count + g - 1) / g * g;
  }

  // Bytes a frame's memset clears in a buffer of the live count: its gridCount bucket within the capacity (at least
  // the size), so that the captured size does not change with every patch.
  template <typename U>
  std::size_t bucketBytes(const DeviceBuffer<U>& b) const {
    return std::min(capacityOf(b), std::size_t(gridCount(int(b.size())))) * sizeof(U);
  }

  // Whether the frame runs as one thread-block cluster launch (kernels/pbd_cluster_frame.cuh).
  bool clusterFrame(const PbdStepParams<T>& p) const {
    return !profile_ && cluster_ok_ && !patched_ && p.solver == PbdSolverKind::Jacobi && n_ <= p.cluster_max_particles &&
           !(p.chebyshev_rho > T(0));
  }

  // Whether the frame runs as one cooperative grid launch (kernels/pbd_grid_frame.cuh): only a frame launched directly
  // (no graph, or the first frame of a new model, as every cutting frame that converts spheres is). There one launch
  // replaces ~170 whose host cost the frame would pay; replayed from a graph, the per-block launches were faster
  // (H100, liver-sized block: 1.03 against 1.09 ms; docs/pbd.md).
  bool gridFrame(const PbdStepParams<T>& p) const {
    return direct_frame_ && !profile_ && grid_cap_ > 0 && !patched_ && p.solver == PbdSolverKind::Jacobi && n_ > 0 &&
           n_ <= p.grid_max_particles && int(blocks_.size()) <= kMaxFusedBlocks && !clusterFrame(p);
  }

  // Records a frame that is launched as it is recorded (no capture): the grid frame's case (gridFrame).
  void recordDirectFrame(const PbdStepParams<T>& p) {
    direct_frame_ = true;
    recordFrame(p);
    direct_frame_ = false;
  }

  // Whether the frame is one kernel (fused, cluster or grid), which takes the counts as arguments.
  bool singleKernelFrame(const PbdStepParams<T>& p) const {
    const bool jacobi = p.solver == PbdSolverKind::Jacobi;
    const bool whole_frame = clusterFrame(p) || gridFrame(p);
    // The single-block frame beats per-block launches for Gauss-Seidel up to thousands of spheres (one launch
    // instead of one per colour) but for Jacobi only up to a few hundred (H100: 1008 spheres 0.23 ms per
    // iteration fused against 0.029 ms on launches), whatever fused_max_particles asks.
    const int fused_limit = jacobi ? std::min(p.fused_max_particles, kFusedJacobiMaxParticles) : p.fused_max_particles;
    // The single-block kernel does not carry the Chebyshev iterates (the grid frame does; the cluster frame does not).
    return whole_frame || (!profile_ && n_ > 0 && n_ <= fused_limit && int(blocks_.size()) <= kMaxFusedBlocks &&
                       !(p.chebyshev_rho > T(0)));
  }

  // Enqueues one whole frame on stream_ (captured into a graph, or run directly). No host synchronisation.
  void recordFrame(const PbdStepParams<T>& p) {
    const T dt = p.frame_dt / T(p.substeps);
    const T damp = std::exp(-p.damping * dt);
    const unsigned gn = blocksFor(gridCount(n_));
    const int* live_n = patched_ ? live_.data() : nullptr;
    pbd::SolveContext<T> ctx;
    ctx.x = x_.data();
    ctx.w = w_.data();
    ctx.mass = masses_.data();
    ctx.rotation = rotations_.data();
    ctx.xpbd = p.xpbd;
    ctx.dt = dt;
    ctx.jacobi = p.solver == PbdSolverKind::Jacobi;
    ctx.omega = p.jacobi_omega;
    ctx.rotation_iterations = p.rotation_iterations;

    const bool cluster = clusterFrame(p);
    const bool grid = gridFrame(p);
    const bool fused = singleKernelFrame(p);
    last_path_ = cluster ? "cluster" : grid ? "grid" : fused ? "fused" : "launches";
    if (fused) {
      FusedFrame<T> f;
      f.n = n_;
      f.substeps = p.substeps;
      f.iterations = p.iterations;
      f.x = x_.data();
      f.v = v_.data();
      f.x_prev = x_prev_.data();
      f.w = w_.data();
      f.r = radii_.data();
      f.inset = insetPtr();
      f.g = p.gravity;
      f.damp = damp;
      f.dt = dt;
      f.ctx = ctx;
      f.nblocks = int(blocks_.size());
      for (std::size_t b = 0; b < blocks_.size(); ++b) {
        DeviceBlock<T>& d = blocks_[b];
        f.blocks[b].view = view(d);
        f.blocks[b].order = d.order.data();
        f.blocks[b].color_offsets = d.color_offsets_dev.data();
        f.blocks[b].colors = int(d.color_offsets.size()) - 1;
        f.blocks[b].multipliers = int(d.lambda.size());
        f.blocks[b].solve = d.solve;
      }
      f.n_kin = n_kin_;
      f.kin_ids = kin_ids_.data();
      f.kin_from = kin_from_.data();
      f.kin_to = kin_to_.data();
      f.n_att = n_att_;
      f.att_ids = att_ids_.data();
      f.att_from = att_from_.data();
      f.att_to = att_to_.data();
      f.att_comp = att_comp_.data();
      f.att_lambda = att_lambda_.data();
      f.planes = planes_.data();
      f.boxes = boxes_.data();
      f.tools_from = tools_from_.data();
      f.tools_to = tools_to_.data();
      f.np = n_planes_;
      f.nb = n_boxes_;
      f.nt = n_tools_;
      f.staged = staged_;
      if (grid) {
        launchGridFrame(p, f);
      } else if (cluster) {
        ClusterLaunch launch(cluster_split_.ctas, cluster_bytes_, stream_);
        INC_CUDA(cudaLaunchKernelEx(&launch.cfg, clusterFrameKernel<T>, f, cluster_split_));
        INC_CUDA_LAUNCH("pbd cluster frame");
      } else {
        fusedFrameKernel<T><<<1, kFusedThreads, staged_ ? stage_bytes_ : 0, stream_>>>(f);
        INC_CUDA_LAUNCH("pbd fused frame");
      }
    }
    const bool cheb = !fused && p.chebyshev_rho > T(0);
    ChebyshevArgs<T> ch = cheb ? chebyshevArgs() : ChebyshevArgs<T>();
    // The contact kernels step every multiplier too: one thread each (a grid over the particles alone left each
    // thread a serial loop of ~10 dependent loads on the liver-sized model, +10 us per iteration on the H100).
    const unsigned gcont = cheb ? std::max(gn, blocksFor(ch.total)) : gn;
    for (int s = 0; s < (fused ? 0 : p.substeps); ++s) {
      const T t_start = T(s) / T(p.substeps), t_end = T(s + 1) / T(p.substeps);
      std::size_t ev = stageBegin();
      if (n_ > 0) {
        predictKernel<T><<<gn, kThreads, 0, stream_>>>(n_, live_n, x_.data(), v_.data(), x_prev_.data(), w_.data(), p.gravity,
                                                       damp, dt, cheb ? cheb_x1_.data() : nullptr);
        INC_CUDA_LAUNCH("pbd predict");
      }
      if (n_kin_ > 0) {
        kinematicKernel<T><<<blocksFor(n_kin_), kThreads, 0, stream_>>>(n_kin_, x_.data(), kin_ids_.data(),
                                                                        kin_from_.data(), kin_to_.data(), t_end);
        INC_CUDA_LAUNCH("pbd kinematic");
      }
      for (DeviceBlock<T>& d : blocks_)
        if (d.lambda.size())
          INC_CUDA(cudaMemsetAsync(d.lambda.data(), 0, bucketBytes(d.lambda), stream_));
      if (n_att_ > 0) INC_CUDA(cudaMemsetAsync(att_lambda_.data(), 0, att_lambda_.bytes(), stream_));
      stageEnd(0, ev);

      // Jacobi without attachments: the iteration's contacts ride on the last block's gather (gatherContactKernel).
      int last_solved = -1;
      for (std::size_t bi = 0; bi < blocks_.size(); ++bi)
        if (blocks_[bi].solve && blocks_[bi].count > 0) last_solved = int(bi);
      const bool fuse_contacts = ctx.jacobi && !profile_ && n_att_ == 0 && last_solved >= 0 && n_ > 0;
      for (int it = 0; it < p.iterations; ++it) {
        if (cheb) ch.mode = pbd::chebyshevIteration(it, p.iterations, p.chebyshev_rho, ch.weight);
        for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
          DeviceBlock<T>& d = blocks_[bi];
          if (!d.solve || d.count == 0) continue;
          ev = stageBegin();  // profiling: each block is its own record (stage 5 + block index)
          const pbd::BlockView<T> b = view(d);
          const int* live_count = patched_ ? live_.data() + 1 + bi : nullptr;
          if (ctx.jacobi) {
            const int gc = gridCount(d.count);
            if (pbdgroup::usesGroup(b.kind))
              projectGroupKernel<T><<<groupBlocksFor(gc), kThreads, 0, stream_>>>(b, ctx, nullptr, gc, live_count);
            else
              launchProjection(b, ctx, nullptr, gc, live_count, stream_);
            INC_CUDA_LAUNCH("pbd project (jacobi)");
            if (fuse_contacts && int(bi) == last_solved) {
              gatherContactKernel<T><<<gcont, kThreads, 0, stream_>>>(n_, live_n, b, x_.data(), radii_.data(), insetPtr(), x_prev_.data(), w_.data(),
                                                                   planes_.data(), n_planes_, boxes_.data(), n_boxes_,
                                                                   tools_from_.data(), tools_to_.data(), n_tools_, t_start, t_end, ch);
              INC_CUDA_LAUNCH("pbd gather + contacts");
            } else {
              gatherKernel<T><<<gn, kThreads, 0, stream_>>>(n_, live_n, b, x_.data());
              INC_CUDA_LAUNCH("pbd gather");
            }
          } else {
            for (std::size_t k = 0; k + 1 < d.color_offsets.size(); ++k) {
              const int c0 = d.color_offsets[k], cnt = d.color_offsets[k + 1] - c0;
              if (cnt == 0) continue;
              if (pbdgroup::usesGroup(b.kind))
                projectGroupKernel<T><<<groupBlocksFor(cnt), kThreads, 0, stream_>>>(b, ctx, d.order.data() + c0, cnt,
                                                                                     nullptr);
              else
                launchProjection(b, ctx, d.order.data() + c0, cnt, nullptr, stream_);
              INC_CUDA_LAUNCH("pbd project (colour)");
            }
          }
          stageEnd(5 + int(bi), ev);
        }
        ev = stageBegin();
        if (n_att_ > 0) {
          attachKernel<T><<<blocksFor(n_att_), kThreads, 0, stream_>>>(n_att_, x_.data(), w_.data(), att_ids_.data(),
                                                                       att_from_.data(), att_to_.data(),
                                                                       att_comp_.data(), att_lambda_.data(), p.xpbd,
                                                                       dt, t_end);
          INC_CUDA_LAUNCH("pbd attachments");
        }
        stageEnd(1, ev);
        ev = stageBegin();
        if (n_ > 0 && !fuse_contacts) {
          contactKernel<T><<<gcont, kThreads, 0, stream_>>>(n_, live_n, x_.data(), radii_.data(), insetPtr(), x_prev_.data(), w_.data(), planes_.data(),
                                                         n_planes_, boxes_.data(), n_boxes_, tools_from_.data(),
                                                         tools_to_.data(), n_tools_, t_start, t_end, ch);
          INC_CUDA_LAUNCH("pbd contacts");
        }
        stageEnd(2, ev);
      }
      ev = stageBegin();
      if (n_ > 0) {
        velocityKernel<T><<<gn, kThreads, 0, stream_>>>(n_, live_n, x_.data(), x_prev_.data(), v_.data(), T(1) / dt);
        INC_CUDA_LAUNCH("pbd velocities");
      }
      stageEnd(3, ev);
    }

    std::size_t ev = stageBegin();
    if (rotation_block_ >= 0 && !blocks_[rotation_block_].solve && blocks_[rotation_block_].count > 0) {
      DeviceBlock<T>& d = blocks_[rotation_block_];
      rotationKernel<T><<<blocksFor(gridCount(d.count)), kThreads, 0, stream_>>>(view(d), ctx,
                                                                                patched_ ? live_.data() + 1 + rotation_block_ : nullptr);
      INC_CUDA_LAUNCH("pbd rotations");
    }
    stageEnd(1, ev);

    ev = stageBegin();
    if (n_ > 0) {
      const bool have_volume = p.volume_preservation && have_volume_data_;
      if (have_volume) {
        volumeActiveKernel<T><<<gn, kThreads, 0, stream_>>>(n_, x_.data(), rest_radii_.data(), tools_to_.data(),
                                                            n_volume_tools_, p.volume_influence, active_.data());
        INC_CUDA_LAUNCH("pbd volume active");
        for (int pass = 0; pass < p.volume_passes; ++pass) {
          radiusKernel<T><<<gn, kThreads, 0, stream_>>>(n_, x_.data(), radii_.data(), radii_next_.data(),
                                                        rest_radii_.data(), rest_cell_.data(), ov_off_.data(),
                                                        ov_ids_.data(), samples_.data(), int(samples_.size()),
                                                        active_.data(), p.max_radius_growth, p.bisection_steps);
          INC_CUDA_LAUNCH("pbd radii");
          INC_CUDA(cudaMemcpyAsync(radii_.data(), radii_next_.data(), radii_.bytes(), cudaMemcpyDeviceToDevice, stream_));
        }
      } else {
        INC_CUDA(cudaMemsetAsync(active_.data(), 0, bucketBytes(active_), stream_));
        restRadiiKernel<T><<<gn, kThreads, 0, stream_>>>(n_, live_n, radii_.data(), rest_radii_.data());
        INC_CUDA_LAUNCH("pbd rest radii");
      }
    }
    stageEnd(4, ev);
  }

  // Residual, finiteness and volume statistics: small partial reductions downloaded once per frame (the
  // frame's one synchronisation, needed to report them).
  void summarize(const PbdStepParams<T>& p, PbdFrameStats& st) {
    // All partials go to slices of one buffer: the frame's one synchronisation and one small download.
    const T dt = p.frame_dt / T(p.substeps);
    double* part = partials_.data();
    std::size_t rcount = 0;
    int nd = 0;
    FinishPlan plan;
    for (DeviceBlock<T>& d : blocks_) {
      if (d.kind != PbdConstraintKind::Distance || !d.solve || d.count == 0) continue;
      plan.used[2 * nd] = plan.used[2 * nd + 1] = reduceBlocksFor(d.count);
      residualKernel<T><<<plan.used[2 * nd], kThreads, 0, stream_>>>(view(d), x_.data(), p.xpbd, dt,
                                                                  part + std::size_t(2 * nd) * kReduceBlocks,
                                                                  part + std::size_t(2 * nd + 1) * kReduceBlocks);
      INC_CUDA_LAUNCH("pbd residual");
      rcount += std::size_t(d.count);
      ++nd;
    }
    double* sum_part = part + std::size_t(2 * nd) * kReduceBlocks;
    if (n_ > 0) {
      plan.used[2 * nd] = plan.used[2 * nd + 1] = plan.used[2 * nd + 2] = reduceBlocksFor(n_);
      summaryKernel<T><<<plan.used[2 * nd], kThreads, 0, stream_>>>(n_, x_.data(), v_.data(), radii_.data(),
                                                                 rest_radii_.data(), active_.data(), sum_part,
                                                                 sum_part + kReduceBlocks, sum_part + 2 * kReduceBlocks);
      INC_CUDA_LAUNCH("pbd summary");
    }
    const int groups = 2 * nd + (n_ > 0 ? 3 : 0);
    if (groups == 0) {
      INC_CUDA(cudaStreamSynchronize(stream_));
      return;
    }
    // The totals live after the partials (partials_ has room: see setModel and commit).
    double* totals = part + std::size_t(groups) * kReduceBlocks;
    plan.nd = nd;
    finishPartialsKernel<<<groups, kReduceBlocks, 0, stream_>>>(part, plan, totals);
    INC_CUDA_LAUNCH("pbd summary totals");
    host_partials_.resize(std::size_t(groups));
    summary_staging_.download(host_partials_.data(), totals, std::size_t(groups), stream_);  // waits for the frame
    const double* h = host_partials_.data();
    double rmax = 0, rsum = 0;
    for (int b = 0; b < nd; ++b) {
      rmax = std::max(rmax, h[2 * b]);
      rsum += h[2 * b + 1];
    }
    st.residual_max = rmax;
    st.residual_rms = rcount ? std::sqrt(rsum / double(rcount)) : 0.0;
    if (n_ > 0) {
      const double* hs = h + 2 * nd;
      const long long bad = (long long)hs[0], act = (long long)hs[1];
      const double rat = std::max(1.0, hs[2]);
      st.volume_active = int(act);
      st.max_radius_ratio = rat;
      if (bad < n_) {
        st.finite = false;
        st.failure_particle = bad;
      }
    }
  }

  cudaStream_t stream_ = nullptr;
  cudaGraphExec_t graph_exec_ = nullptr;
  BulkUpload bulk_;  // setModel's uploads
  GraphKey<T> graph_key_;
  bool has_coloring_ = true;  // Gauss-Seidel needs every solved block coloured (pbdModelHasColoring)
  DeviceBuffer<T> cheb_weights_;           // the grid frame's per-iteration weights
  std::vector<T> cheb_weights_host_;
  int grid_cap_ = -1;                      // resident blocks of the grid frame (planGrid); -1 not asked yet
  bool direct_frame_ = false;              // the frame being recorded is launched directly, not captured
  DeviceBuffer<Vec3<T>> cheb_x1_, cheb_x2_, cheb_a1_, cheb_a2_;  // Chebyshev: positions, attachment multipliers
  std::uint64_t topo_version_ = 0;  // bumped by a new model and by a reallocation: the captured graph holds pointers
  DeviceBuffer<int> live_;          // the counts the frame's kernels read (uploadLive)
  std::vector<std::int32_t> kin_ids_host_;  // what kin_ids_ holds
  PinnedStaging summary_staging_, kin_to_staging_;
  bool live_dirty_ = true;
  std::uint64_t last_direct_topo_ = ~std::uint64_t(0);
  bool patched_ = false;            // a block was rebuilt on the device: no colouring (Jacobi only)
  int summary_every_ = 1;
  std::uint64_t frame_count_ = 0;
  DeviceBuffer<std::uint32_t> sort_keys_, sort_keys_out_;
  DeviceBuffer<std::int32_t> sort_vals_;
  DeviceBuffer<unsigned char> cub_temp_;
  std::vector<cudaEvent_t> events_;
  std::vector<ProfRecord> prof_;
  bool profile_ = false;

  int n_ = 0, n_planes_ = 0, n_boxes_ = 0, n_kin_ = 0, n_att_ = 0, n_tools_ = 0, n_volume_tools_ = 0, rotation_block_ = -1;
  bool have_volume_data_ = false;
  std::vector<T> host_rest_radii_;
  DeviceBuffer<T> inset_;  // PbdModel::contact_inset where the model has one
  bool has_inset_ = false;
  const T* insetPtr() const { return has_inset_ ? inset_.data() : nullptr; }
  DeviceBuffer<Vec3<T>> rest_positions_, x_, v_, x_prev_, kin_from_, kin_to_, samples_, att_from_, att_to_, att_lambda_;
  DeviceBuffer<T> masses_, inv_mass_, w_, rest_radii_, radii_, radii_next_, rest_cell_, att_comp_;
  DeviceBuffer<pbd::Quat<T>> rotations_;
  DeviceBuffer<std::uint8_t> active_, fixed_scratch_;
  DeviceBuffer<std::int32_t> kin_ids_, ov_off_, ov_ids_, att_ids_;
  DeviceBuffer<pbd::PlaneCollider<T>> planes_;
  DeviceBuffer<pbd::BoxCollider<T>> boxes_;
  DeviceBuffer<pbd::CapsuleCollider<T>> tools_from_, tools_to_;
  DeviceBuffer<double> partials_;           // reduction partials: per distance block (max, sum), then summary
  std::vector<double> host_partials_;
  struct ClusterBlockMeta {
    std::vector<std::int32_t> offsets;  // host copy of the block's constraint -> slot offsets
    std::vector<std::int32_t> particle_slots;  // and of its particle -> slot CSR entries
    bool solve = true;
    int kind = 0;
  };
  std::vector<ClusterBlockMeta> cluster_meta_;
  const char* last_path_ = "launches";      // the frame kernel recordFrame chose last (reported in the stats)
  std::vector<DeviceBuffer<std::int32_t>> cluster_home_;  // ClusterSplit::slot_home, per block
  DeviceBuffer<long long> cluster_profile_;  // INCISION_PBD_CLUSTER_PROFILE: cycles per phase kind and CTA
  int cluster_planned_for_ = -1;            // the cluster_ctas the current plan was made for (-1: none)
  bool cluster_ok_ = false;                 // the cluster frame can run this model (planCluster)
  ClusterSplit cluster_split_;
  std::size_t cluster_bytes_ = 0;
  bool staged_ = false;                     // fused kernel stages particles in shared memory
  std::size_t stage_bytes_ = 0;
  std::vector<DeviceBlock<T>> blocks_;
};

}  // namespace

template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdCudaBackend() {
  return std::make_unique<PbdCudaBackend<T>>();
}

template <typename T>
PbdDevicePatch<T>* pbdDevicePatch(PbdBackend<T>& backend) {
  return dynamic_cast<PbdDevicePatch<T>*>(&backend);
}

template PbdDevicePatch<float>* pbdDevicePatch<float>(PbdBackend<float>&);
template PbdDevicePatch<double>* pbdDevicePatch<double>(PbdBackend<double>&);

template std::unique_ptr<PbdBackend<float>> makePbdCudaBackend<float>();
template std::unique_ptr<PbdBackend<double>> makePbdCudaBackend<double>();

}  // namespace inc::cuda
