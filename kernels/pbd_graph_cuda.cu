// The CUDA PBD backend's frame graph: what a captured frame depends on, when it is (re)captured, when a frame is
// launched directly instead, the replay.
#include <algorithm>
#include <cstddef>

#include "kernels/graph_capture.h"
#include "kernels/pbd_backend_cuda.cuh"

namespace inc::cuda {

namespace {

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
         x.chebyshev_rho == y.chebyshev_rho && a.kinematic == b.kinematic && a.tools == b.tools &&
         a.volume_tools == b.volume_tools && a.attached == b.attached && std::equal(a.ptrs, a.ptrs + 11, b.ptrs) &&
         a.n == b.n && std::equal(a.counts, a.counts + kMaxLiveBlocks, b.counts) && a.patched == b.patched &&
         a.topo == b.topo;
}

}  // namespace

// The frame replayed from its graph, re-captured first when what it depends on changed (GraphKey), or launched
// directly right after a new model.
template <typename T>
void PbdCudaBackend<T>::launchGraphFrame(const PbdStepParams<T>& p, const PbdFrameInput<T>& in) {
  GraphKey<T> key;
  key.p = p;
  key.kinematic = in.kinematic_ids.size();
  key.tools = in.tools_from.size();
  key.volume_tools = std::size_t(in.volumeToolCount());
  key.attached = in.attach_ids.size();
  const void* ptrs[11] = {kin_ids_.data(),  kin_from_.data(), kin_to_.data(),    tools_from_.data(),
                          tools_to_.data(), w_.data(),        att_ids_.data(),   att_from_.data(),
                          att_to_.data(),   att_comp_.data(), att_lambda_.data()};
  std::copy(ptrs, ptrs + 11, key.ptrs);
  // The single-kernel frames take the counts as arguments: a new count is a new graph.
  const bool exact = framePath(p) != FramePath::Launches;
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
}

template void PbdCudaBackend<float>::launchGraphFrame(const PbdStepParams<float>&, const PbdFrameInput<float>&);
template void PbdCudaBackend<double>::launchGraphFrame(const PbdStepParams<double>&, const PbdFrameInput<double>&);

}  // namespace inc::cuda
