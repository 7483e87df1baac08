// A frame of the CUDA PBD backend: advanceFrame's orchestration, the frame's inputs and Chebyshev iterates, the
// per-block launches of a substep, stage profiling.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "kernels/pbd_backend_cuda.cuh"
#include "kernels/pbd_contact_kernels.cuh"
#include "kernels/pbd_group_projection.cuh"
#include "kernels/pbd_particle_kernels.cuh"
#include "kernels/pbd_projection_kernels.cuh"
#include "physics/pbd_chebyshev.h"

namespace inc::cuda {

namespace {

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

}  // namespace

template <typename T>
PbdFrameStats PbdCudaBackend<T>::advanceFrame(const PbdStepParams<T>& p, const PbdFrameInput<T>& in) {
  validateFrameInput(std::size_t(n_), p, in);
  direct_frame_ = false;  // also after a frame whose recording threw
  PbdFrameStats st;
  // Per-frame inputs (synchronous uploads: the previous frame has finished with these buffers).
  INC_CUDA(cudaStreamSynchronize(stream_));
  uploadFrameInput(in);
  uploadLive();

  const bool jacobi = p.solver == PbdSolverKind::Jacobi;
  if (!jacobi && patched_)
    throw InputError("pbd frame", "solver",
                     "the model was patched on the device (no colouring): use the Jacobi solver");
  if (!jacobi && !has_coloring_)
    throw InputError("pbd frame", "solver",
                     "the model was built without a colouring (Jacobi only): use the Jacobi solver");
  if (p.chebyshev_rho > T(0)) ensureChebyshev(p);
  if (!jacobi)
    for (const DeviceBlock<T>& d : blocks_)
      if (d.solve) st.colors += int(d.color_offsets.size()) - 1;
  st.iterations = p.substeps * p.iterations;
  // The cluster frame's plan sets kernel attributes: outside any capture, before the frame is recorded.
  if (jacobi && !patched_ && n_ <= p.cluster_max_particles) planCluster(p.cluster_ctas);
  if (jacobi && !patched_ && n_ <= p.grid_max_particles) planGrid();

  if (p.profile_stages)
    recordProfiledFrame(p, st);
  else
    recordTimedFrame(p, in, st);
  st.path = last_path_;
  if (cluster_split_.profile && std::string(last_path_) == "cluster") printClusterProfile();
  if (summaryDue() || p.profile_stages) summarize(p, st);
  ++frame_count_;
  return st;
}

// The frame recorded with event pairs around its stages (launched directly, per-block launches), then timed.
template <typename T>
void PbdCudaBackend<T>::recordProfiledFrame(const PbdStepParams<T>& p, PbdFrameStats& st) {
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
      st.stages.push_back({std::string(kindName(blocks_[bi].kind)) + "#" + std::to_string(bi), ms[5 + bi]});
}

// The frame replayed from its graph or launched directly, between two events; the "frame" stage on summary frames.
template <typename T>
void PbdCudaBackend<T>::recordTimedFrame(const PbdStepParams<T>& p, const PbdFrameInput<T>& in, PbdFrameStats& st) {
  ensureEvents(2);
  INC_CUDA(cudaEventRecord(events_[0], stream_));
  if (p.use_graph)
    launchGraphFrame(p, in);
  else
    recordDirectFrame(p);
  INC_CUDA(cudaEventRecord(events_[1], stream_));
  if (summaryDue()) {
    INC_CUDA(cudaEventSynchronize(events_[1]));
    float e = 0.f;
    INC_CUDA(cudaEventElapsedTime(&e, events_[0], events_[1]));
    st.stages.push_back({"frame", double(e)});
  }
}

template <typename T>
void PbdCudaBackend<T>::uploadFrameInput(const PbdFrameInput<T>& in) {
  // Inverse masses of this frame: kinematic particles get w = 0 (a device copy and a scatter of zeros on the
  // stream, after the synchronous id upload; no per-particle host array crosses the bus).
  // A grasp holds the same particles frame after frame: their ids cross the bus once.
  if (in.kinematic_ids != kin_ids_host_) {
    kin_ids_.upload(in.kinematic_ids);
    kin_ids_host_ = in.kinematic_ids;
  }
  if (n_ > 0)
    INC_CUDA(
        cudaMemcpyAsync(w_.data(), inv_mass_.data(), std::size_t(n_) * sizeof(T), cudaMemcpyDeviceToDevice, stream_));
  if (!in.kinematic_ids.empty())
    PbdParticleKernels<T>::zeroKinematic(blocksFor(std::int64_t(in.kinematic_ids.size())), stream_,
                                         int(in.kinematic_ids.size()), w_.data(), kin_ids_.data());
  if (in.kinematic_from_positions) {
    // The start positions gathered on the device (the previous frame's work is ordered before this on stream_).
    kin_from_.resize(in.kinematic_ids.size());
    if (!in.kinematic_ids.empty())
      PbdParticleKernels<T>::gatherKinematic(blocksFor(std::int64_t(in.kinematic_ids.size())), stream_,
                                             int(in.kinematic_ids.size()), x_.data(), kin_ids_.data(),
                                             kin_from_.data());
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
template <typename T>
void PbdCudaBackend<T>::ensureChebyshev(const PbdStepParams<T>& p) {
  if (patched_)
    throw InputError("pbd frame", "chebyshev_rho", "not supported on a model patched on the device (tearing): use 0");
  if (int(blocks_.size()) + 1 > kMaxChebyshevLists)
    throw InputError("pbd frame", "chebyshev_rho",
                     "supported for up to " + std::to_string(kMaxChebyshevLists - 1) +
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
template <typename T>
ChebyshevArgs<T> PbdCudaBackend<T>::chebyshevArgs() {
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

template <typename T>
void PbdCudaBackend<T>::ensureEvents(std::size_t k) {
  while (events_.size() < k) {
    cudaEvent_t e;
    INC_CUDA(cudaEventCreate(&e));
    events_.push_back(e);
  }
}

// Profiling only: event pairs around each stage launch group (summed per stage after the frame).
template <typename T>
std::size_t PbdCudaBackend<T>::stageBegin() {
  if (!profile_) return 0;
  const std::size_t k = 2 + 2 * prof_.size();
  ensureEvents(k + 2);
  INC_CUDA(cudaEventRecord(events_[k], stream_));
  return k;
}

template <typename T>
void PbdCudaBackend<T>::stageEnd(int stage, std::size_t k) {
  if (!profile_) return;
  INC_CUDA(cudaEventRecord(events_[k + 1], stream_));
  prof_.push_back({stage, k, k + 1});
}

// Records a frame that is launched as it is recorded (no capture): the grid frame's case (kernels/pbd_frame_path.cuh).
template <typename T>
void PbdCudaBackend<T>::recordDirectFrame(const PbdStepParams<T>& p) {
  direct_frame_ = true;
  recordFrame(p);
  direct_frame_ = false;
}

// Enqueues one whole frame on stream_ (captured into a graph, or run directly). No host synchronisation.
template <typename T>
void PbdCudaBackend<T>::recordFrame(const PbdStepParams<T>& p) {
  LaunchFrame lf;
  lf.dt = p.frame_dt / T(p.substeps);
  lf.damp = std::exp(-p.damping * lf.dt);
  lf.gn = blocksFor(gridCount(n_));
  lf.live_n = patched_ ? live_.data() : nullptr;
  pbd::SolveContext<T>& ctx = lf.ctx;
  ctx.x = x_.data();
  ctx.w = w_.data();
  ctx.mass = masses_.data();
  ctx.rotation = rotations_.data();
  ctx.xpbd = p.xpbd;
  ctx.dt = lf.dt;
  ctx.jacobi = p.solver == PbdSolverKind::Jacobi;
  ctx.omega = p.jacobi_omega;
  ctx.rotation_iterations = p.rotation_iterations;

  const FramePath path = framePath(p);
  last_path_ = framePathName(path);
  const bool whole_frame = path != FramePath::Launches;
  if (whole_frame) launchWholeFrame(path, p, wholeFrameArgs(p, ctx, lf.dt, lf.damp));
  lf.cheb = !whole_frame && p.chebyshev_rho > T(0);
  if (lf.cheb) lf.ch = chebyshevArgs();
  // The contact kernels step every multiplier too: one thread each (a grid over the particles alone left each
  // thread a serial loop of ~10 dependent loads on the liver-sized model, +10 us per iteration on the H100).
  lf.gcont = lf.cheb ? std::max(lf.gn, blocksFor(lf.ch.total)) : lf.gn;
  // Jacobi without attachments: the iteration's contacts ride on the last block's gather (gatherContactKernel).
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi)
    if (blocks_[bi].solve && blocks_[bi].count > 0) lf.last_solved = int(bi);
  lf.fuse_contacts = ctx.jacobi && !profile_ && n_att_ == 0 && lf.last_solved >= 0 && n_ > 0;
  lf.scene.r = radii_.data();
  lf.scene.inset = insetPtr();
  lf.scene.x_prev = x_prev_.data();
  lf.scene.w = w_.data();
  lf.scene.planes = planes_.data();
  lf.scene.np = n_planes_;
  lf.scene.boxes = boxes_.data();
  lf.scene.nb = n_boxes_;
  lf.scene.tools_from = tools_from_.data();
  lf.scene.tools_to = tools_to_.data();
  lf.scene.nt = n_tools_;
  for (int s = 0; s < (whole_frame ? 0 : p.substeps); ++s) recordSubstep(p, lf, s);
  recordRotations(lf);
  recordRadii(p, lf);
}

// The arguments of the single-launch frames (fused, cluster, grid): the model's and the frame's device views.
template <typename T>
FusedFrame<T> PbdCudaBackend<T>::wholeFrameArgs(const PbdStepParams<T>& p, const pbd::SolveContext<T>& ctx, T dt,
                                                T damp) {
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
  return f;
}

// One substep of per-block launches: prediction, kinematic targets and cleared multipliers; the iterations; the
// velocities.
template <typename T>
void PbdCudaBackend<T>::recordSubstep(const PbdStepParams<T>& p, LaunchFrame& lf, int s) {
  const T t_start = T(s) / T(p.substeps), t_end = T(s + 1) / T(p.substeps);
  std::size_t ev = stageBegin();
  if (n_ > 0)
    PbdParticleKernels<T>::predict(lf.gn, stream_, n_, lf.live_n, x_.data(), v_.data(), x_prev_.data(), w_.data(),
                                   p.gravity, lf.damp, lf.dt, lf.cheb ? cheb_x1_.data() : nullptr);
  if (n_kin_ > 0)
    PbdParticleKernels<T>::kinematic(blocksFor(n_kin_), stream_, n_kin_, x_.data(), kin_ids_.data(), kin_from_.data(),
                                     kin_to_.data(), t_end);
  for (DeviceBlock<T>& d : blocks_)
    if (d.lambda.size()) INC_CUDA(cudaMemsetAsync(d.lambda.data(), 0, bucketBytes(d.lambda), stream_));
  if (n_att_ > 0) INC_CUDA(cudaMemsetAsync(att_lambda_.data(), 0, att_lambda_.bytes(), stream_));
  stageEnd(0, ev);

  for (int it = 0; it < p.iterations; ++it) recordIteration(p, lf, it, t_start, t_end);
  ev = stageBegin();
  if (n_ > 0)
    PbdParticleKernels<T>::velocity(lf.gn, stream_, n_, lf.live_n, x_.data(), x_prev_.data(), v_.data(), T(1) / lf.dt);
  stageEnd(3, ev);
}

// One iteration of per-block launches: every solved block's projection (Jacobi: then its gather), the attachments,
// the contacts (Jacobi without attachments: with the last block's gather).
template <typename T>
void PbdCudaBackend<T>::recordIteration(const PbdStepParams<T>& p, LaunchFrame& lf, int it, T t_start, T t_end) {
  const pbd::SolveContext<T>& ctx = lf.ctx;
  if (lf.cheb) lf.ch.mode = pbd::chebyshevIteration(it, p.iterations, p.chebyshev_rho, lf.ch.weight);
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
    DeviceBlock<T>& d = blocks_[bi];
    if (!d.solve || d.count == 0) continue;
    const std::size_t ev = stageBegin();  // profiling: each block is its own record (stage 5 + block index)
    const pbd::BlockView<T> b = view(d);
    const int* live_count = patched_ ? live_.data() + 1 + bi : nullptr;
    if (ctx.jacobi) {
      PbdProjectionKernels<T>::jacobi(stream_, b, ctx, gridCount(d.count), live_count);
      if (lf.fuse_contacts && int(bi) == lf.last_solved)
        PbdContactKernels<T>::gatherContacts(lf.gcont, stream_, n_, lf.live_n, b, x_.data(), lf.scene, t_start, t_end,
                                             lf.ch);
      else
        PbdProjectionKernels<T>::gather(lf.gn, stream_, n_, lf.live_n, b, x_.data());
    } else {
      for (std::size_t k = 0; k + 1 < d.color_offsets.size(); ++k) {
        const int c0 = d.color_offsets[k], cnt = d.color_offsets[k + 1] - c0;
        if (cnt == 0) continue;
        PbdProjectionKernels<T>::colour(stream_, b, ctx, d.order.data() + c0, cnt);
      }
    }
    stageEnd(5 + int(bi), ev);
  }
  std::size_t ev = stageBegin();
  if (n_att_ > 0)
    PbdProjectionKernels<T>::attachments(blocksFor(n_att_), stream_, n_att_, x_.data(), w_.data(), att_ids_.data(),
                                         att_from_.data(), att_to_.data(), att_comp_.data(), att_lambda_.data(), p.xpbd,
                                         lf.dt, t_end);
  stageEnd(1, ev);
  ev = stageBegin();
  if (n_ > 0 && !lf.fuse_contacts)
    PbdContactKernels<T>::contacts(lf.gcont, stream_, n_, lf.live_n, x_.data(), lf.scene, t_start, t_end, lf.ch);
  stageEnd(2, ev);
}

// The cluster rotations of a shape-matching block that is not solved (the Laplacian's rest frames).
template <typename T>
void PbdCudaBackend<T>::recordRotations(const LaunchFrame& lf) {
  const std::size_t ev = stageBegin();
  if (rotation_block_ >= 0 && !blocks_[rotation_block_].solve && blocks_[rotation_block_].count > 0) {
    DeviceBlock<T>& d = blocks_[rotation_block_];
    PbdProjectionKernels<T>::rotations(blocksFor(gridCount(d.count)), stream_, view(d), lf.ctx,
                                       patched_ ? live_.data() + 1 + rotation_block_ : nullptr);
  }
  stageEnd(1, ev);
}

// The sphere radii: the volume-preserving solve near the tools, or the rest radii.
template <typename T>
void PbdCudaBackend<T>::recordRadii(const PbdStepParams<T>& p, const LaunchFrame& lf) {
  const std::size_t ev = stageBegin();
  if (n_ > 0) {
    const bool have_volume = p.volume_preservation && have_volume_data_;
    if (have_volume) {
      PbdParticleKernels<T>::volumeActive(lf.gn, stream_, n_, x_.data(), rest_radii_.data(), tools_to_.data(),
                                          n_volume_tools_, p.volume_influence, active_.data());
      for (int pass = 0; pass < p.volume_passes; ++pass) {
        PbdParticleKernels<T>::radius(lf.gn, stream_, n_, x_.data(), radii_.data(), radii_next_.data(),
                                      rest_radii_.data(), rest_cell_.data(), ov_off_.data(), ov_ids_.data(),
                                      samples_.data(), int(samples_.size()), active_.data(), p.max_radius_growth,
                                      p.bisection_steps);
        INC_CUDA(cudaMemcpyAsync(radii_.data(), radii_next_.data(), radii_.bytes(), cudaMemcpyDeviceToDevice, stream_));
      }
    } else {
      INC_CUDA(cudaMemsetAsync(active_.data(), 0, bucketBytes(active_), stream_));
      PbdParticleKernels<T>::restRadii(lf.gn, stream_, n_, lf.live_n, radii_.data(), rest_radii_.data());
    }
  }
  stageEnd(4, ev);
}

// Defined here, called from the other files of the backend (the class is instantiated in pbd_solver_cuda.cu).
template PbdFrameStats PbdCudaBackend<float>::advanceFrame(const PbdStepParams<float>&, const PbdFrameInput<float>&);
template PbdFrameStats PbdCudaBackend<double>::advanceFrame(const PbdStepParams<double>&, const PbdFrameInput<double>&);
template ChebyshevArgs<float> PbdCudaBackend<float>::chebyshevArgs();
template ChebyshevArgs<double> PbdCudaBackend<double>::chebyshevArgs();
template void PbdCudaBackend<float>::recordDirectFrame(const PbdStepParams<float>&);
template void PbdCudaBackend<double>::recordDirectFrame(const PbdStepParams<double>&);
template void PbdCudaBackend<float>::recordFrame(const PbdStepParams<float>&);
template void PbdCudaBackend<double>::recordFrame(const PbdStepParams<double>&);

}  // namespace inc::cuda
