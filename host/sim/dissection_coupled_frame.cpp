// The dissection's coupled frame (section 5.3): nodal points and PBD spheres advance in turn.
// They exchange the interface spheres' springs (eqs. 11-12) and positions (eq. 13) every interval.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "base/elapsed_ms.h"
#include "host/sim/dissection_simulation_impl.h"
#include "physics/pbd_block.h"

namespace inc::dissection {

namespace {

// The stage times of `add` summed into `into`, stage by stage.
void addStages(std::vector<StageTime>& into, const std::vector<StageTime>& add) {
  for (const StageTime& s : add) {
    auto it = std::find_if(into.begin(), into.end(), [&](const StageTime& t) { return t.stage == s.stage; });
    if (it == into.end())
      into.push_back(s);
    else
      it->ms += s.ms;
  }
}

void addMlsStats(MlsFrameStats& into, const MlsFrameStats& ms) {
  into.substeps += ms.substeps;
  into.ms_integrate += ms.ms_integrate;
  into.ms_coupling += ms.ms_coupling;
  into.ms_stress += ms.ms_stress;
  into.ms_forces += ms.ms_forces;
  into.ms_reduce += ms.ms_reduce;
  into.ms_substeps += ms.ms_substeps;
  into.totals = ms.totals;
  into.substeps_needed = ms.substeps_needed;
}

}  // namespace

// K = cutting.exchanges_per_frame intervals of frame_dt / K. Each: the springs' anchors from the PBD spheres
// (held over the interval), the nodal points advance (MLS, eqs. 4-10, with the springs' share eqs. 11-12 on
// the interface spheres' points every substep), then the interface spheres take their eq. 13 positions as
// kinematic targets of the PBD step over the same interval (pbd_substeps_per_exchange substeps of
// cutting.pbd_iterations iterations). Tools and grasps are interpolated over the frame.
template <typename T>
void DissectionSimulation<T>::coupledFrame(double frame_dt, const PbdFrameInput<T>& in, FrameOutcome& out) {
  const int K = scene_.cutting.exchanges_per_frame;
  const double dt = frame_dt / K;
  const PbdStepParams<T> p = exchangeParams(dt);
  InterfaceAnchors anchors = interfaceAnchors();
  out.pbd = PbdFrameStats{};
  for (int e = 0; e < K; ++e) {
    if (!advancePoints(e, K, dt, out)) break;
    const PbdFrameInput<T> ie = exchangeInput(e, K, in, anchors);
    if (!advanceSpheres(e, K, p, ie, out)) break;
  }
}

// One exchange's PBD step: pbd_substeps_per_exchange substeps (scaled by the guard's retries) of
// cutting.pbd_iterations iterations (0: the scene's).
template <typename T>
PbdStepParams<T> DissectionSimulation<T>::exchangeParams(double dt) const {
  PbdStepParams<T> p = params_;
  p.frame_dt = T(dt);
  p.substeps = std::max(1, int(std::ceil(scene_.cutting.pbd_substeps_per_exchange * substep_scale_ - 1e-9)));
  if (scene_.cutting.pbd_iterations > 0) p.iterations = scene_.cutting.pbd_iterations;
  if (preload_ && directFrameFits(p)) p.use_graph = false;  // no capture beside the workers' loads
  return p;
}

template <typename T>
typename DissectionSimulation<T>::InterfaceAnchors DissectionSimulation<T>::interfaceAnchors() const {
  const ActiveStroke& a = *active_;
  InterfaceAnchors anchors;
  a.region->interfacePositions(anchors.ids, anchors.targets);
  anchors.from.resize(anchors.ids.size());
  for (std::size_t k = 0; k < anchors.ids.size(); ++k)
    anchors.from[k] = state_.positions[std::size_t(a.base_to_pbd[std::size_t(anchors.ids[k])])];
  anchors.kinematic.assign(model_.size(), 0);
  for (std::int32_t b : anchors.ids) anchors.kinematic[std::size_t(a.base_to_pbd[std::size_t(b)])] = 1;
  return anchors;
}

// Exchange e's MLS half: the nodal points advance over dt with the blade over the interval as a contact and the
// interface springs anchored at the spheres' current positions (eqs. 11-12). False when they went non-finite.
template <typename T>
bool DissectionSimulation<T>::advancePoints(int e, int K, double dt, FrameOutcome& out) {
  ActiveStroke& a = *active_;
  NodalRegion& region = *a.region;
  if (bladeContact()) {
    const double b0 = double(e) / K, b1 = double(e + 1) / K;
    region.setBlade(lerpBlade(frame_blade_.from, frame_blade_.to, b0),
                    lerpBlade(frame_blade_.from, frame_blade_.to, b1), scene_.cutting.blade_radius_m,
                    scene_.cutting.blade_friction);
  } else {
    region.setBlade({}, {}, 0.0);
  }
  const auto pbdPosition = [&](std::int32_t b) {
    return Vec3d(state_.positions[std::size_t(a.base_to_pbd[std::size_t(b)])]);
  };
  const auto cm = std::chrono::steady_clock::now();
  const MlsFrameStats ms = region.advance(dt, scene_.cutting.mls_substeps_per_exchange, pbdPosition);
  timers_.mls_ms += msSince(cm);
  addMlsStats(out.mls, ms);
  if (ms.totals.finite) return true;
  out.mls_finite = false;
  if (e > 0) backend_->getState(state_);  // the exchanges before read the positions alone
  return false;
}

// Exchange e's PBD input: the interface spheres move kinematically from their last targets to their eq. 13
// positions now; the attachments (but those of kinematic spheres, held by their points now) and the tools are
// interpolated over the interval.
template <typename T>
PbdFrameInput<T> DissectionSimulation<T>::exchangeInput(int e, int K, const PbdFrameInput<T>& in,
                                                        InterfaceAnchors& anchors) {
  const ActiveStroke& a = *active_;
  const auto c0 = std::chrono::steady_clock::now();
  a.region->interfacePositions(anchors.ids, anchors.targets);  // eq. 13
  PbdFrameInput<T> ie;
  const T s0 = T(double(e) / K), s1 = T(double(e + 1) / K);
  for (std::size_t k = 0; k < anchors.ids.size(); ++k) {
    ie.kinematic_ids.push_back(a.base_to_pbd[std::size_t(anchors.ids[k])]);
    ie.kinematic_from.push_back(anchors.from[k]);
    ie.kinematic_to.push_back(Vec3<T>(anchors.targets[k]));
    anchors.from[k] = Vec3<T>(anchors.targets[k]);
  }
  for (std::size_t k = 0; k < in.attach_ids.size(); ++k) {
    if (anchors.kinematic[std::size_t(in.attach_ids[k])]) continue;  // held by its points now
    ie.attach_ids.push_back(in.attach_ids[k]);
    ie.attach_from.push_back(pbd::lerp(in.attach_from[k], in.attach_to[k], s0));
    ie.attach_to.push_back(pbd::lerp(in.attach_from[k], in.attach_to[k], s1));
    ie.attach_compliance.push_back(in.attach_compliance[k]);
  }
  for (std::size_t k = 0; k < in.tools_from.size(); ++k) {
    ie.tools_from.push_back(pbd::lerpCapsule(in.tools_from[k], in.tools_to[k], s0));
    ie.tools_to.push_back(pbd::lerpCapsule(in.tools_from[k], in.tools_to[k], s1));
  }
  ie.volume_tools = in.volume_tools;
  timers_.exchange_ms += msSince(c0);
  return ie;
}

// Exchange e's PBD half (eq. 13 on the interface spheres), its stats into the frame's; then the positions the next
// exchange anchors to (the whole state after the last one). False when the spheres went non-finite.
template <typename T>
bool DissectionSimulation<T>::advanceSpheres(int e, int K, const PbdStepParams<T>& p, const PbdFrameInput<T>& ie,
                                             FrameOutcome& out) {
  PbdFrameStats& st = out.pbd;
  const PbdFrameStats ps = backend_->advanceFrame(p, ie);
  addStages(st.stages, ps.stages);
  st.residual_max = ps.residual_max;
  st.residual_rms = ps.residual_rms;
  st.colors = ps.colors;
  st.iterations += ps.iterations;
  st.volume_active = ps.volume_active;
  st.max_radius_ratio = ps.max_radius_ratio;
  const auto c1 = std::chrono::steady_clock::now();
  if (e + 1 < K && ps.finite)
    backend_->getPositions(state_.positions);  // the next exchange's anchors (the rest after the last one)
  else
    backend_->getState(state_);
  timers_.exchange_ms += msSince(c1);
  ++out.exchanges;
  out.pbd_substeps += p.substeps;
  if (ps.finite) return true;
  st.finite = false;
  st.failure_particle = ps.failure_particle;
  return false;
}

// This file's members for the two precisions makeDissectionSimulation builds.
#define INC_DISSECTION_COUPLED_FRAME(T)                                                                             \
  template void DissectionSimulation<T>::coupledFrame(double, const PbdFrameInput<T>&, FrameOutcome&);              \
  template PbdStepParams<T> DissectionSimulation<T>::exchangeParams(double) const;                                  \
  template DissectionSimulation<T>::InterfaceAnchors DissectionSimulation<T>::interfaceAnchors() const;             \
  template bool DissectionSimulation<T>::advancePoints(int, int, double, FrameOutcome&);                            \
  template PbdFrameInput<T> DissectionSimulation<T>::exchangeInput(int, int, const PbdFrameInput<T>&,               \
                                                                   InterfaceAnchors&);                              \
  template bool DissectionSimulation<T>::advanceSpheres(int, int, const PbdStepParams<T>&, const PbdFrameInput<T>&, \
                                                        FrameOutcome&);
INC_DISSECTION_COUPLED_FRAME(float)
INC_DISSECTION_COUPLED_FRAME(double)
#undef INC_DISSECTION_COUPLED_FRAME

}  // namespace inc::dissection
