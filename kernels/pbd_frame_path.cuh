// Which of the CUDA PBD backend's four frame paths runs a frame: the one place the choice is made.
//
// The four paths (PbdFrameStats::path names them; checked in this order, the first that applies runs):
//  1. "cluster": the whole Jacobi frame in one thread-block cluster launch (clusterFrameKernel,
//     kernels/pbd_cluster_frame.cuh). Chosen when the solver is Jacobi, the model was not patched on the device,
//     n <= cluster_max_particles (default 256), there is no Chebyshev acceleration, stages are not profiled, and
//     planCluster found a cluster that runs here (sm_90+, at most kMaxFusedBlocks blocks, the particle replica
//     fits a CTA's shared memory, at least one cluster resident).
//     Measured faster than per-block launches up to ~250 spheres (docs/pbd.md).
//  2. "grid": the whole Jacobi frame in one cooperative grid launch (gridFrameKernel, kernels/pbd_grid_frame.cuh).
//     Only for a frame launched directly, not replayed from a graph (use_graph off, or the first frame of a new
//     model: every cutting frame that converts spheres), when the solver is Jacobi, the model was not patched,
//     0 < n <= grid_max_particles (default 2048), it has at most kMaxFusedBlocks blocks, the device launches
//     cooperative kernels, stages are not profiled and the cluster path does not apply. Chebyshev included.
//     Measured faster than direct per-block launches up to ~1000 spheres, slower from ~3000 (H100); replayed from a
//     graph the per-block launches were faster (liver-sized block: 1.03 against 1.09 ms; docs/pbd.md).
//  3. "fused": the whole frame in one thread block (fusedFrameKernel, kernels/pbd_fused_frame.cuh), Jacobi or
//     Gauss-Seidel. Chosen when 0 < n <= fused_max_particles (default 4096), for Jacobi also n <=
//     kFusedJacobiMaxParticles (256), at most kMaxFusedBlocks blocks, no Chebyshev, stages not profiled.
//  4. "launches": one launch per phase (prediction, each block's projection and gather or each colour, attachments,
//     contacts, velocities) per iteration and substep (kernels/pbd_particle_kernels.cu and its siblings). Every
//     other frame: larger models, more than kMaxFusedBlocks blocks, Chebyshev frames off the grid path, profiled
//     frames (PbdStepParams::profile_stages).
// With use_graph, paths 1, 3 and 4 are captured into a CUDA graph once the model has stayed the same for a frame,
// and replayed (kernels/pbd_graph_cuda.cu); the first frame of a new model is launched directly. On every path the
// cluster rotations and sphere radii follow as separate launches.
#pragma once

#include <algorithm>

#include "kernels/pbd_frame_data.cuh"
#include "model/pbd_model.h"

namespace inc::cuda {

enum class FramePath { Cluster, Grid, Fused, Launches };

// PbdFrameStats::path of each.
inline const char* framePathName(FramePath path) {
  switch (path) {
    case FramePath::Cluster: return "cluster";
    case FramePath::Grid: return "grid";
    case FramePath::Fused: return "fused";
    case FramePath::Launches: return "launches";
  }
  return "launches";
}

// The single-block frame beats per-block launches for Gauss-Seidel up to thousands of spheres (one launch
// instead of one per colour) but for Jacobi only up to a few hundred (H100: 1008 spheres 0.23 ms per
// iteration fused against 0.029 ms on launches), whatever fused_max_particles asks.
constexpr int kFusedJacobiMaxParticles = 256;

// What the choice depends on besides the step parameters: the backend's state for this frame.
struct FramePathFacts {
  int particles = 0;
  int blocks = 0;                // constraint blocks of the model
  bool profiling = false;        // stages are timed (PbdStepParams::profile_stages): per-block launches only
  bool patched = false;          // the model was patched on the device (tearing): counts read on the device
  bool direct = false;           // the frame is launched as it is recorded, not captured into a graph
  bool cluster_planned = false;  // planCluster found a cluster that runs this model here
  int grid_resident_blocks = 0;  // planGrid: the grid frame's resident blocks (0: no cooperative launch)
};

// The first of the four paths (the list at the top of this file) whose conditions hold.
template <typename T>
FramePath chooseFramePath(const PbdStepParams<T>& p, const FramePathFacts& f) {
  const bool jacobi = p.solver == PbdSolverKind::Jacobi;
  const bool chebyshev = p.chebyshev_rho > T(0);
  const bool few_blocks = f.blocks <= kMaxFusedBlocks;
  if (!f.profiling && f.cluster_planned && !f.patched && jacobi && f.particles <= p.cluster_max_particles && !chebyshev)
    return FramePath::Cluster;
  if (f.direct && !f.profiling && f.grid_resident_blocks > 0 && !f.patched && jacobi && f.particles > 0 &&
      f.particles <= p.grid_max_particles && few_blocks)
    return FramePath::Grid;
  // The single-block kernel does not carry the Chebyshev iterates (the grid frame does; the cluster frame does not).
  const int fused_limit = jacobi ? std::min(p.fused_max_particles, kFusedJacobiMaxParticles) : p.fused_max_particles;
  if (!f.profiling && f.particles > 0 && f.particles <= fused_limit && few_blocks && !chebyshev)
    return FramePath::Fused;
  return FramePath::Launches;
}

}  // namespace inc::cuda
