// Tearing driver: PBD frame, tearing step (CPU or CUDA), model rebuild after a topology change, removal tools.
#include "host/tear/tearing_driver.h"

#include "host/backends/solver_factory.h"

#include <chrono>

#include "base/elapsed_ms.h"
#include "model/input_error.h"
#if INCISION_HAVE_CUDA
#include "kernels/pbd_device_cuda.h"
#endif

namespace inc {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

template <typename T>
TearingDriver<T>::TearingDriver(TearSheet<T> sheet, const TearParams<T>& tear, const TearModelOptions& model_opt,
                                const PbdStepParams<T>& step, BackendKind kind)
    : sheet_(std::move(sheet)), tear_(tear), model_opt_(model_opt), step_(step) {
  model_opt_.coloring = step_.solver == PbdSolverKind::GaussSeidel;  // Jacobi never reads the colouring
  if (!(tear_.random_range >= T(0)) || !(tear_.t_lo > T(0)) || !(tear_.t_hi < T(1)) || !(tear_.t_lo <= tear_.t_hi))
    throw InputError("tearing", "random_range", "need range >= 0 and 0 < t_lo <= t_hi < 1");
  if (!(tear_.break_strain > T(0))) throw InputError("tearing", "break_strain", "must be > 0");
  if (!(tear_.min_area_ratio > T(0) && tear_.min_area_ratio < T(1)))
    throw InputError("tearing", "min_area_ratio", "must be in (0, 1)");
  for (std::size_t i = 0; i < sheet_.size(); ++i)
    if (!(sheet_.k[i] > T(0)) || !(sheet_.tau_f[i] > T(0)))
      throw InputError("tearing", "material", "k and tau_f must be > 0 (particle " + std::to_string(i) + ")");
  tear_backend_ = makeTearStepBackend<T>(kind);
  // The PBD solve runs on the same kind as the tearing step (CUDA: positions, velocities and the constraint
  // model stay on the device during the solve; the tearing step reads the frame's end state on the host).
  pbd_ = makePbdBackend<T>(tear_backend_->kind());
  resetModel();
}

template <typename T>
void TearingDriver<T>::resetModel() {
  syncHost();
  sheet_.rebuildTopology();
  const PbdModel<T> model = buildTearPbdModel(sheet_, model_opt_);
  pbd_->setModel(model);
  const std::size_t n = sheet_.size();
  state_.positions = sheet_.x;
  state_.velocities = sheet_.v;
  state_.radii.assign(n, T(0));
  state_.rotations.assign(n, pbd::Quat<T>{});
  pbd_->setState(state_);
  // Device-resident (docs/tearing.md): the Jacobi solver needs no colouring, so a tearing frame can patch the
  // model on the device; Gauss-Seidel keeps the host rebuild (its colouring is a host algorithm).
  resident_ = allow_device_resident && step_.solver == PbdSolverKind::Jacobi &&
              tear_backend_->attach(*pbd_, sheet_, model_opt_, int(model.blocks.size()));
  host_stale_ = topo_stale_ = false;
  setSummaryEvery(summary_every_);
}

template <typename T>
void TearingDriver<T>::setSummaryEvery(int k) {
  if (k < 1) throw InputError("tearing", "summary_every", "must be >= 1");
  summary_every_ = k;
#if INCISION_HAVE_CUDA
  if (cuda::PbdDevicePatch<T>* patch = cuda::pbdDevicePatch<T>(*pbd_)) patch->setSummaryEvery(resident_ ? k : 1);
#endif
}

template <typename T>
void TearingDriver<T>::syncHost() const {
  if (!resident_ || !host_stale_) return;
  tear_backend_->download(sheet_, topo_stale_);
  if (topo_stale_) sheet_.rebuildTopology();  // the device has its own adjacency; the host's only on demand
  host_stale_ = topo_stale_ = false;
}

template <typename T>
TearFrameStats TearingDriver<T>::advanceResident(const std::vector<std::int32_t>& grasp_ids,
                                                 const std::vector<Vec3<T>>& grasp_to) {
  TearFrameStats st;
  st.device_resident = true;
  const std::size_t n = tear_backend_->residentSize();
  for (std::int32_t id : grasp_ids)
    if (id < 0 || std::size_t(id) >= n) throw InputError("tearing", "grasp", "particle out of range");
  PbdFrameInput<T> in;
  in.kinematic_ids = grasp_ids;
  in.kinematic_to = grasp_to;
  in.kinematic_from_positions = true;  // the grasped particles' start positions never leave the device
  PbdStepParams<T> sp = step_;
  sp.profile_stages = sp.profile_stages || profile;
  auto t0 = Clock::now();
  st.pbd = pbd_->advanceFrame(sp, in);
  st.solve_ms = msSince(t0);
  host_stale_ = true;
  st.stages.push_back({"solve", st.solve_ms});
  if (tearing_enabled && st.pbd.finite) {
    t0 = Clock::now();
    if (tear_backend_->stepResident(tear_, sheet_.step, st, profile) > 0) topo_stale_ = true;
    ++sheet_.step;
    st.tear_ms = msSince(t0) - st.rebuild_ms;  // stepResident fills rebuild_ms and its stages
  }
  for (const StageTime& s : st.pbd.stages) st.stages.push_back({"pbd:" + s.stage, s.ms});
  return st;
}

template <typename T>
TearFrameStats TearingDriver<T>::advance(const std::vector<std::int32_t>& grasp_ids,
                                         const std::vector<Vec3<T>>& grasp_to) {
  if (grasp_ids.size() != grasp_to.size())
    throw InputError("tearing", "grasp", "ids and targets must have equal sizes");
  if (resident_) return advanceResident(grasp_ids, grasp_to);
  TearFrameStats st;
  PbdFrameInput<T> in;
  in.kinematic_ids = grasp_ids;
  for (std::int32_t id : grasp_ids) {
    if (id < 0 || std::size_t(id) >= sheet_.size()) throw InputError("tearing", "grasp", "particle out of range");
    in.kinematic_from.push_back(sheet_.x[id]);
  }
  in.kinematic_to = grasp_to;
  PbdStepParams<T> sp = step_;
  sp.profile_stages = sp.profile_stages || profile;
  auto t0 = Clock::now();
  st.pbd = pbd_->advanceFrame(sp, in);
  const double frame_ms = msSince(t0);
  t0 = Clock::now();
  pbd_->getState(state_);
  sheet_.x = state_.positions;
  sheet_.v = state_.velocities;
  const double download_ms = msSince(t0);
  st.solve_ms = frame_ms + download_ms;
  st.stages.push_back({"solve", frame_ms});
  st.stages.push_back({"download_state", download_ms});
  if (tearing_enabled && st.pbd.finite) {
    t0 = Clock::now();
    const int created = tear_backend_->step(sheet_, tear_, st);
    st.tear_ms = msSince(t0);
    st.stages.push_back({"tear_step", st.tear_ms});
    if (created > 0) {
      // The host rebuild: adjacency, PBD model, upload (timed apart for the breakdown).
      t0 = Clock::now();
      sheet_.rebuildTopology();
      const double topo_ms = msSince(t0);
      t0 = Clock::now();
      const PbdModel<T> model = buildTearPbdModel(sheet_, model_opt_);
      const double model_ms = msSince(t0);
      t0 = Clock::now();
      pbd_->setModel(model);
      const std::size_t n = sheet_.size();
      state_.positions = sheet_.x;
      state_.velocities = sheet_.v;
      state_.radii.assign(n, T(0));
      state_.rotations.assign(n, pbd::Quat<T>{});
      pbd_->setState(state_);
      const double upload_ms = msSince(t0);
      st.rebuild_ms = topo_ms + model_ms + upload_ms;
      st.stages.push_back({"host_topology", topo_ms});
      st.stages.push_back({"host_model", model_ms});
      st.stages.push_back({"upload_model", upload_ms});
    }
  }
  for (const StageTime& s : st.pbd.stages) st.stages.push_back({"pbd:" + s.stage, s.ms});
  return st;
}

template <typename T>
int TearingDriver<T>::removeParticles(const std::vector<std::uint8_t>& mark, bool debris_fringe,
                                      std::vector<std::int32_t>* remap) {
  syncHost();
  const int removed = removeTearParticles(sheet_, mark, debris_fringe, tear_, remap);
  resetModel();
  return removed;
}

template <typename T>
int TearingDriver<T>::tearOut(const std::vector<std::uint8_t>& mark, const Vec3<T>& lift, int frames, int* removed) {
  if (mark.size() != particleCount()) throw InputError("tearing", "mark", "one flag per particle");
  if (frames < 1) throw InputError("tearing", "frames", "must be >= 1");
  std::vector<std::int32_t> ids;
  std::vector<Vec3<T>> base;
  const TearSheet<T>& s = sheet();
  for (std::size_t i = 0; i < mark.size(); ++i)
    if (mark[i]) {
      ids.push_back(std::int32_t(i));
      base.push_back(s.x[i]);
    }
  int splits = 0;
  std::vector<Vec3<T>> to(ids.size());
  for (int f = 0; f < frames; ++f) {
    const T s = T(f + 1) / T(frames);
    for (std::size_t k = 0; k < ids.size(); ++k) to[k] = base[k] + lift * s;
    splits += advance(ids, to).splits;  // splits append particles: the gripped ids stay valid
  }
  std::vector<std::uint8_t> grip(particleCount(), 0);
  for (std::int32_t id : ids) grip[id] = 1;
  const int r = removeParticles(grip, false);
  if (removed) *removed = r;
  return splits;
}

template class TearingDriver<float>;
template class TearingDriver<double>;

}  // namespace inc
