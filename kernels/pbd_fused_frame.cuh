// The PBD frame of a small model in one thread block: every phase a block-strided loop, phases separated by
// __syncthreads(), particles optionally staged in shared memory.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>

#include "kernels/pbd_frame_data.cuh"
#include "kernels/pbd_group_projection.cuh"
#include "physics/pbd_block.h"
#include "physics/pbd_collision.h"
#include "physics/pbd_rotation.h"

namespace inc::cuda {

// Small models (the haptic case): the whole constraint loop of a frame in one thread block. Each phase is a
// block-strided loop over the same physics calls as the per-phase kernels (kernels/pbd_*_kernels.cu), separated by
// __syncthreads() (which orders this block's global-memory writes), so the result equals the multi-launch
// path bit for bit while paying one launch per frame instead of one per block, colour and iteration.
constexpr int kFusedThreads = 1024;

// Dynamic shared memory the fused kernel needs to stage n particles (rotations, positions, w, mass).
template <typename T>
inline std::size_t fusedStageBytes(int n) {
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
              pbdgroup::projectGroup(fb.view, base + tid / pbdgroup::kGroup,
                                     base + tid / pbdgroup::kGroup < fb.view.count, ctx, lane);
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
        pbd::projectAttachment(x[id], w[id], pbd::lerp(f.att_from[q], f.att_to[q], t_end), f.att_comp[q], ctx.xpbd,
                               f.dt, f.att_lambda[q]);
      }
      __syncthreads();
      for (int i = tid; i < f.n; i += nth)
        if (w[i] > T(0))
          x[i] = pbd::resolveContacts(x[i], f.r[i], f.inset ? f.inset[i] : T(0), f.x_prev + i, f.planes, f.np, f.boxes,
                                      f.nb, f.tools_from, f.tools_to, f.nt, t_start, t_end);
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

}  // namespace inc::cuda
