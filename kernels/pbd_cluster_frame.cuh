// The Jacobi PBD frame of a small model in one thread-block cluster: every CTA keeps a replica of the particles in
// shared memory, phases are separated by hardware cluster barriers.
#pragma once

#include <cooperative_groups.h>
#include <cuda_runtime.h>

#include <cstdint>

#include "kernels/pbd_frame_data.cuh"
#include "kernels/pbd_group_projection.cuh"
#include "physics/pbd_block.h"

namespace inc::cuda {

// Why a cluster: a small Jacobi frame (10 iterations x 4 substeps, three blocks) is 40 x 3 dependent
// project -> gather steps of a few microseconds of work each. One launch per step pays a launch gap each time;
// one thread block runs out of lanes (a cluster constraint takes 16). A cluster of up to 16 CTAs has the lanes
// and a barrier in hardware (barrier.cluster), and its CTAs read and write each other's shared memory
// (distributed shared memory), so positions never leave the SMs during the frame. Measured (docs/pbd.md) it
// wins up to ~250 spheres; above, the per-iteration latency of its phases costs more than the launches save.
// The work's layout over the CTAs: ClusterSplit (kernels/pbd_frame_data.cuh).

// Launch configuration of a cluster of `ctas` CTAs (the grid is one cluster), for the occupancy query and the
// launch alike.
struct ClusterLaunch {
  cudaLaunchAttribute attr[1];
  cudaLaunchConfig_t cfg = {};
  ClusterLaunch(int ctas, std::size_t smem_bytes, cudaStream_t stream) {
    attr[0].id = cudaLaunchAttributeClusterDimension;
    attr[0].val.clusterDim.x = unsigned(ctas);
    attr[0].val.clusterDim.y = 1;
    attr[0].val.clusterDim.z = 1;
    cfg.gridDim = dim3(unsigned(ctas));
    cfg.blockDim = dim3(kClusterThreads);
    cfg.dynamicSmemBytes = smem_bytes;
    cfg.stream = stream;
    cfg.attrs = attr;
    cfg.numAttrs = 1;
  }
  ClusterLaunch(const ClusterLaunch&) = delete;  // cfg points into attr
  ClusterLaunch& operator=(const ClusterLaunch&) = delete;
};

extern __shared__ __align__(16) unsigned char cluster_stage[];

namespace clusterframe {

// Jacobi gather of the owned particles [p0, p1), kGroup lanes per particle: each lane fetches one slot's
// correction from the CTA that computed it, and the group's first lane adds them in ascending slot order, as
// pbd::gatherCorrection does (the same sum, bit for bit). Every thread of the block must call it.
template <typename T>
__device__ inline void gatherOwned(cooperative_groups::cluster_group& cl, const pbd::BlockView<T>& view,
                                   const std::int32_t* home, Vec3<T>* sslot, Vec3<T>* sx, int p0, int p1) {
  constexpr int G = pbdgroup::kGroup;
  const int lane = int(threadIdx.x) % G, base_lane = int(threadIdx.x) & 31 & ~(G - 1);
  const int per_pass = int(blockDim.x) / G;
  for (int base = p0; base < p1; base += per_pass) {
    const int i = base + int(threadIdx.x) / G;
    const bool valid = i < p1;
    const std::int32_t k0 = valid ? view.particle_offsets[i] : 0, k1 = valid ? view.particle_offsets[i + 1] : 0;
    Vec3<T> sum;
    for (std::int32_t kb = 0; __any_sync(0xffffffffu, k0 + kb < k1); kb += G) {
      const std::int32_t k = k0 + kb + lane;
      Vec3<T> v;
      if (k < k1) {
        const std::int32_t h = home[k];
        v = *cl.map_shared_rank(sslot + (h & 0xffffff), unsigned(h) >> 24);
      }
      for (int j = 0; j < G; ++j) {
        const T vx = __shfl_sync(0xffffffffu, v.x, base_lane + j), vy = __shfl_sync(0xffffffffu, v.y, base_lane + j),
                vz = __shfl_sync(0xffffffffu, v.z, base_lane + j);
        if (k0 + kb + j < k1) sum += Vec3<T>(vx, vy, vz);
      }
    }
    if (valid && lane == 0) sx[i] += sum;
  }
}

// Writes the owned particles' positions [p0, p1) into every other CTA's replica, one (particle, CTA) pair per
// thread.
template <typename T>
__device__ inline void broadcastPositions(cooperative_groups::cluster_group& cl, Vec3<T>* sx, int p0, int p1, int rank,
                                          int ctas) {
  const int others = ctas - 1;
  if (others == 0) return;
  const int pairs = (p1 - p0) * others;
  for (int k = int(threadIdx.x); k < pairs; k += int(blockDim.x)) {
    const int i = p0 + k / others;
    int r = k % others;
    r += r >= rank ? 1 : 0;
    *cl.map_shared_rank(sx + i, r) = sx[i];
  }
}

}  // namespace clusterframe

template <typename T>
__global__ void __launch_bounds__(kClusterThreads, 1) clusterFrameKernel(FusedFrame<T> f, ClusterSplit sp) {
  namespace cg = cooperative_groups;
  cg::cluster_group cl = cg::this_cluster();
  const int rank = int(cl.block_rank()), ctas = sp.ctas;
  const int tid = int(threadIdx.x), nth = int(blockDim.x);
  const int n = f.n;

  pbd::Quat<T>* srot = reinterpret_cast<pbd::Quat<T>*>(cluster_stage);
  Vec3<T>* sx = reinterpret_cast<Vec3<T>*>(srot + n);
  T* sw = reinterpret_cast<T*>(sx + n);
  T* sm = sw + n;
  T* sr = sm + n;
  Vec3<T>* sslot = reinterpret_cast<Vec3<T>*>(sr + n);
  // Diagnostics (sp.profile set): thread 0 adds the SM cycles since the previous mark to a phase kind.
  long long prof[kClusterProfileSlots];
  long long mark = clock64();
  const bool profiling = sp.profile != nullptr && threadIdx.x == 0;
  if (profiling)
    for (int k = 0; k < kClusterProfileSlots; ++k) prof[k] = 0;
  auto tick = [&](int kind) {
    if (!profiling) return;
    const long long now = clock64();
    prof[kind] += now - mark;
    mark = now;
  };

  const bool rotations = f.ctx.rotation != nullptr;
  for (int i = tid; i < n; i += nth) {
    sx[i] = f.x[i];
    sw[i] = f.w[i];
    sm[i] = f.ctx.mass[i];
    sr[i] = f.r[i];
    srot[i] = rotations ? f.ctx.rotation[i] : pbd::Quat<T>();
  }
  // Every CTA must have staged its replica (and be running) before any CTA writes into another's memory.
  cl.sync();

  pbd::SolveContext<T> ctx = f.ctx;
  ctx.x = sx;
  ctx.w = sw;
  ctx.mass = sm;
  ctx.rotation = rotations ? srot : nullptr;
  const int p0 = min(n, rank * sp.chunk), p1 = min(n, p0 + sp.chunk);
  const int lane = tid % pbdgroup::kGroup, per_pass = nth / pbdgroup::kGroup;
  int last_block = -1;
  for (int b = 0; b < f.nblocks; ++b)
    if (f.blocks[b].solve && f.blocks[b].view.count > 0) last_block = b;

  // Attachments then contacts of the owned particles (each attached particle has one attachment), in that
  // order as in the per-launch path; the caller broadcasts and synchronises.
  auto attachAndContact = [&](T t_start, T t_end) {
    for (int q = tid; q < f.n_att; q += nth) {
      const std::int32_t id = f.att_ids[q];
      if (id >= p0 && id < p1)
        pbd::projectAttachment(sx[id], sw[id], pbd::lerp(f.att_from[q], f.att_to[q], t_end), f.att_comp[q], ctx.xpbd,
                               f.dt, f.att_lambda[q]);
    }
    __syncthreads();
    for (int i = p0 + tid; i < p1; i += nth)
      if (sw[i] > T(0))
        sx[i] = pbd::resolveContacts(sx[i], sr[i], f.inset ? f.inset[i] : T(0), f.x_prev + i, f.planes, f.np, f.boxes,
                                     f.nb, f.tools_from, f.tools_to, f.nt, t_start, t_end);
    __syncthreads();
  };

  for (int s = 0; s < f.substeps; ++s) {
    const T t_start = T(s) / T(f.substeps), t_end = T(s + 1) / T(f.substeps);
    for (int i = p0 + tid; i < p1; i += nth) pbd::predictParticle(sx[i], f.v[i], f.x_prev[i], sw[i], f.g, f.damp, f.dt);
    // Multipliers restart each substep; each CTA clears those of the constraints it projects.
    for (int b = 0; b < f.nblocks; ++b) {
      const FusedBlock<T>& fb = f.blocks[b];
      const bool per_slot = fb.view.kind == pbd::kShapeMatching;
      const int k0 = per_slot ? sp.s_split[b][rank] : sp.c_split[b][rank];
      const int k1 = per_slot ? sp.s_split[b][rank + 1] : sp.c_split[b][rank + 1];
      for (int k = k0 + tid; k < k1 && k < fb.multipliers; k += nth) fb.view.lambda[k] = Vec3<T>();
    }
    for (int q = tid; q < f.n_att; q += nth)
      if (f.att_ids[q] >= p0 && f.att_ids[q] < p1) f.att_lambda[q] = Vec3<T>();
    __syncthreads();
    for (int q = tid; q < f.n_kin; q += nth) {
      const std::int32_t id = f.kin_ids[q];
      if (id >= p0 && id < p1) sx[id] = pbd::lerp(f.kin_from[q], f.kin_to[q], t_end);
    }
    __syncthreads();
    clusterframe::broadcastPositions(cl, sx, p0, p1, rank, ctas);
    cl.sync();
    tick(0);

    for (int it = 0; it < f.iterations; ++it) {
      for (int b = 0; b < f.nblocks; ++b) {
        const FusedBlock<T>& fb = f.blocks[b];
        if (!fb.solve || fb.view.count == 0) continue;
        pbd::BlockView<T> view = fb.view;
        const int c0 = sp.c_split[b][rank], c1 = sp.c_split[b][rank + 1];
        // This CTA's slots [s_split[b][rank], ...) land at the start of its slot buffer.
        view.slot_corr = sslot - sp.s_split[b][rank];
        if (pbdgroup::usesGroup(view.kind)) {
          // The same trip count for every thread: all lanes of a warp reach the shuffles.
          for (int base = c0; base < c1; base += per_pass) {
            const int q = base + tid / pbdgroup::kGroup;
            pbdgroup::projectGroup(view, q < c1 ? q : 0, q < c1, ctx, lane);
          }
        } else {
          for (int c = c0 + tid; c < c1; c += nth) pbd::projectConstraint(view, c, ctx);
        }
        if (view.kind == pbd::kShapeMatching && rotations) {
          // The clusters' new rotations (the Laplacian's rest frames, the next projection's warm start) go to
          // every replica before the barrier.
          __syncthreads();
          const int others = ctas - 1, pairs = (c1 - c0) * others;
          for (int k = tid; k < pairs; k += nth) {
            const std::int32_t centre = view.ids[view.offsets[c0 + k / others]];
            int r = k % others;
            r += r >= rank ? 1 : 0;
            *cl.map_shared_rank(srot + centre, r) = srot[centre];
          }
        }
        tick(1 + 4 * b);
        cl.sync();
        tick(2 + 4 * b);
        clusterframe::gatherOwned(cl, view, sp.slot_home[b], sslot, sx, p0, p1);
        __syncthreads();
        if (b == last_block) attachAndContact(t_start, t_end);
        clusterframe::broadcastPositions(cl, sx, p0, p1, rank, ctas);
        tick(3 + 4 * b);
        cl.sync();
        tick(4 + 4 * b);
      }
      if (last_block < 0) {
        attachAndContact(t_start, t_end);
        clusterframe::broadcastPositions(cl, sx, p0, p1, rank, ctas);
        cl.sync();
      }
    }
    const T inv_dt = T(1) / f.dt;
    for (int i = p0 + tid; i < p1; i += nth) f.v[i] = (sx[i] - f.x_prev[i]) * inv_dt;
  }
  for (int i = p0 + tid; i < p1; i += nth) {
    f.x[i] = sx[i];
    if (rotations) f.ctx.rotation[i] = srot[i];
  }
  if (profiling)
    for (int k = 0; k < kClusterProfileSlots; ++k) sp.profile[rank * kClusterProfileSlots + k] = prof[k];
  // No CTA may exit while another can still read its shared memory (the last gather read remote slots; the
  // last broadcast wrote remote positions): the final barrier above covers both.
}

}  // namespace inc::cuda
