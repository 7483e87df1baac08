// The whole Jacobi PBD frame as one cooperative grid launch: the per-block launches' phases, separated by grid-wide
// barriers.
#pragma once

#include <cooperative_groups.h>

#include <cstdint>

#include "kernels/pbd_chebyshev_args.cuh"
#include "kernels/pbd_frame_data.cuh"
#include "kernels/pbd_group_projection.cuh"
#include "kernels/pbd_particle_ops.cuh"
#include "physics/pbd_block.h"
#include "physics/pbd_chebyshev.h"

namespace inc::cuda {

constexpr int kGridFrameThreads = 256;  // a multiple of pbdgroup::kGroup: a cluster's lanes never straddle blocks

template <typename T>
struct GridFrame {
  FusedFrame<T> f;
  ChebyshevArgs<T> ch;              // views of the iterates; mode and weight are set per iteration
  const T* cheb_weights = nullptr;  // weight of each iteration (host: pbd::chebyshevIteration); null: no acceleration
  T cheb_rho = T(0);
  int last_solved = -1;  // without attachments the iteration's contacts ride on this block's gather
};

// Why: on a liver-sized model each Jacobi iteration is six dependent phases (three blocks, each a projection and
// a gather) of a few microseconds of work; as graph kernel nodes every phase also paid a kernel boundary. Here
// the grid stays resident and a phase ends at a grid barrier. Each phase walks the thread indices of its kernel
// (grid-stride) and makes the same physics calls on the same data in the same order as the per-block launches
// (PbdCudaBackend::recordFrame): predict, kinematic targets, zeroed multipliers; per iteration every solved block's
// projection then gather (the last one with the contacts and the Chebyshev step when there are no attachments;
// else the attachments, then the contacts); the velocities.
template <typename T>
__global__ void __launch_bounds__(kGridFrameThreads) gridFrameKernel(GridFrame<T> g) {
  cooperative_groups::grid_group grid = cooperative_groups::this_grid();
  const FusedFrame<T>& f = g.f;
  const int tid = int(blockIdx.x * blockDim.x + threadIdx.x), nth = int(gridDim.x * blockDim.x);
  const int lane = tid % pbdgroup::kGroup, per_pass = nth / pbdgroup::kGroup;
  const bool cheb = g.cheb_weights != nullptr;
  const bool fuse_contacts = f.n_att == 0 && g.last_solved >= 0;
  ChebyshevArgs<T> ch = g.ch;
  const pbd::SolveContext<T>& ctx = f.ctx;
  Vec3<T>* x = f.x;
  for (int s = 0; s < f.substeps; ++s) {
    const T t_start = T(s) / T(f.substeps), t_end = T(s + 1) / T(f.substeps);
    for (int i = tid; i < f.n; i += nth) {
      pbd::predictParticle(x[i], f.v[i], f.x_prev[i], f.w[i], f.g, f.damp, f.dt);
      if (cheb) ch.x1[i] = x[i];  // the substep's first iterate
    }
    for (int b = 0; b < f.nblocks; ++b)
      for (int k = tid; k < f.blocks[b].multipliers; k += nth) f.blocks[b].view.lambda[k] = Vec3<T>();
    for (int k = tid; k < f.n_att; k += nth) f.att_lambda[k] = Vec3<T>();
    if (f.n_kin > 0) {  // a kinematic particle's target replaces its prediction, made by another thread
      grid.sync();
      for (int q = tid; q < f.n_kin; q += nth) x[f.kin_ids[q]] = pbd::lerp(f.kin_from[q], f.kin_to[q], t_end);
    }
    grid.sync();
    for (int it = 0; it < f.iterations; ++it) {
      if (cheb) {
        T unused = T(1);
        ch.mode = pbd::chebyshevIteration(it, f.iterations, g.cheb_rho, unused);
        ch.weight = g.cheb_weights[it];  // the host's value: the device may contract the recursion differently
      }
      for (int b = 0; b < f.nblocks; ++b) {
        const FusedBlock<T>& fb = f.blocks[b];
        if (!fb.solve || fb.view.count == 0) continue;
        if (pbdgroup::usesGroup(fb.view.kind)) {
          // The same trip count for every thread: all lanes of a warp reach the shuffles.
          for (int base = 0; base < fb.view.count; base += per_pass) {
            const int q = base + tid / pbdgroup::kGroup;
            pbdgroup::projectGroup(fb.view, q < fb.view.count ? q : 0, q < fb.view.count, ctx, lane);
          }
        } else {
          for (int c = tid; c < fb.view.count; c += nth) pbd::projectConstraint(fb.view, c, ctx);
        }
        grid.sync();
        if (fuse_contacts && b == g.last_solved) {
          for (int i = tid; i < f.n; i += nth)
            x[i] = endIterationAt(i, x[i] + gatherSum(fb.view, i), f.r, f.inset, f.x_prev, f.w, f.planes, f.np, f.boxes,
                                  f.nb, f.tools_from, f.tools_to, f.nt, t_start, t_end, ch);
          chebyshevMultipliers(ch);
        } else {
          for (int i = tid; i < f.n; i += nth) x[i] += gatherSum(fb.view, i);
        }
        grid.sync();
      }
      if (!fuse_contacts) {
        if (f.n_att > 0) {
          for (int q = tid; q < f.n_att; q += nth) {
            const std::int32_t id = f.att_ids[q];
            pbd::projectAttachment(x[id], f.w[id], pbd::lerp(f.att_from[q], f.att_to[q], t_end), f.att_comp[q],
                                   ctx.xpbd, f.dt, f.att_lambda[q]);
          }
          grid.sync();
        }
        for (int i = tid; i < f.n; i += nth)
          x[i] = endIterationAt(i, x[i], f.r, f.inset, f.x_prev, f.w, f.planes, f.np, f.boxes, f.nb, f.tools_from,
                                f.tools_to, f.nt, t_start, t_end, ch);
        chebyshevMultipliers(ch);
        grid.sync();
      }
    }
    // Each thread's particles are the ones it predicts next substep: no barrier needed before that.
    const T inv_dt = T(1) / f.dt;
    for (int i = tid; i < f.n; i += nth) f.v[i] = (x[i] - f.x_prev[i]) * inv_dt;
  }
}

}  // namespace inc::cuda
