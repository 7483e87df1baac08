// The dissection's conversions: spheres the blade enters become MLS nodal points (section 5.1).
// Prepared in the rest configuration (on workers, preloaded on the GPU, when delayed) and applied with the state of
// the applying frame, so the frame itself only transfers state.
#include "host/sim/dissection_conversion.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <limits>
#include <mutex>

#include "base/elapsed_ms.h"
#include "host/sim/dissection_simulation_impl.h"
#include "model/device_capture_lock.h"
#include "physics/pbd_rotation.h"

namespace inc::dissection {

template <typename T>
StrokePbdPlan<T> planStrokePbd(const ActiveStroke& a, const std::vector<SphereRole>& roles, MetaballPbdOptions opt) {
  StrokePbdPlan<T> p;
  p.spheres = uncutSpheres(a.base, &roles, p.base_to_pbd);
  for (std::size_t b = 0; b < a.base.size(); ++b)
    if (p.base_to_pbd[b] >= 0) p.pbd_to_base.push_back(std::int32_t(b));
  // A sphere none of whose base links reaches a cut sphere keeps its link set, hence its rest cell volume.
  std::vector<double> known;
  if (a.base_cell_volume.size() == a.base.size()) {
    std::vector<char> lost(a.base.size(), 0);
    for (const auto& e : a.base.links) {
      if (p.base_to_pbd[std::size_t(e[0])] < 0) lost[std::size_t(e[1])] = 1;
      if (p.base_to_pbd[std::size_t(e[1])] < 0) lost[std::size_t(e[0])] = 1;
    }
    known.assign(p.spheres.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t i = 0; i < p.spheres.size(); ++i)
      if (!lost[std::size_t(p.pbd_to_base[i])]) known[i] = a.base_cell_volume[std::size_t(p.pbd_to_base[i])];
  }
  opt.known_cell_volumes = std::move(known);
  // A kept sphere's inset depends on its own rest ball alone: the base model's value, not a new surface query.
  if (a.base_contact_inset.size() == a.base.size()) {
    opt.known_contact_insets.resize(p.spheres.size());
    for (std::size_t i = 0; i < p.spheres.size(); ++i)
      opt.known_contact_insets[i] = a.base_contact_inset[std::size_t(p.pbd_to_base[i])];
  }
  const auto t0 = std::chrono::steady_clock::now();
  p.built = buildMetaballPbdModel<T>(p.spheres, opt);
  p.build_ms = msSince(t0);
  return p;
}

// Prepares the conversion of the spheres `hit` (none: the new strip cuts supports only) in the rest configuration
// (NodalRegion::prepareConversion, the stroke's next PBD model): with cutting.conversion_delay_frames 1 that work
// runs on workers beside this frame and the conversion is applied at the next frame's start with the state of then
// (applyConversion); with 0, now.
template <typename T>
void DissectionSimulation<T>::launchConversion(std::unique_ptr<PendingConversion<T>> pc,
                                               std::vector<std::int32_t> hit) {
  NodalRegion& region = *active_->region;
  const SweptSurface& swept = active_->swept;  // nothing extends it before the conversion is applied
  PendingConversion<T>* p = pc.get();
  p->launched_at = time_;
  p->cut = !hit.empty();
  const bool delayed = scene_.cutting.conversion_delay_frames > 0;
  // The region's half (samples, supports, groups, MLS model) and the PBD half (the stroke's next model) read
  // only rest data; delayed, the region's half starts from a copy (advance() goes on with the current data).
  // Delayed on the GPU, each half also loads its model into the spare device buffers (preload_), so that the
  // applying frame only swaps them in and transfers the state.
  const bool preload = delayed && preload_;
  const auto mlsHalf = [p, &region, &swept, delayed, preload, hit] {
    const auto t0 = std::chrono::steady_clock::now();
    NodalRest from = delayed ? region.restCopy() : region.takeRest();
    p->mls =
        p->cut ? region.prepareConversion(std::move(from), hit, swept) : region.prepareStrip(std::move(from), p->fresh);
    if (preload) region.preload(p->mls);
    p->mls_prepare_ms = msSince(t0);
  };
  std::function<void()> pbdHalf = [] {};
  if (p->cut)
    pbdHalf = [this, p, preload, roles = region.rolesAfter(hit)] {
      const auto t0 = std::chrono::steady_clock::now();
      p->pbd = planStrokePbd<T>(*active_, roles, pbdOptions({}, false));
      if (preload) preloadStrokePbd(p->pbd);
      p->pbd_prepare_ms = msSince(t0);
    };
  converting_ = std::move(pc);
  if (delayed) {
    convert_worker_.start(mlsHalf);
    if (p->cut) prepare_pbd_worker_.start(std::move(pbdHalf));
  } else {
    if (p->cut)
      timers_.convert_wait_ms += convert_worker_.runBeside(mlsHalf, pbdHalf);
    else
      mlsHalf();  // a strip's supports: well under a millisecond, not worth a thread hand-over
    applyConversion();
  }
}

// Brings a prepared conversion in with the state of now: the new points start rigidly attached to their spheres'
// current state, the existing points keep theirs, the stroke's next PBD model takes the current positions and
// velocities of the spheres it keeps.
template <typename T>
void DissectionSimulation<T>::applyConversion() {
  if (!converting_) return;
  const auto c0 = std::chrono::steady_clock::now();
  convert_worker_.wait();
  prepare_pbd_worker_.wait();
  timers_.convert_wait_ms += msSince(c0);
  std::unique_ptr<PendingConversion<T>> pc = std::move(converting_);
  NodalRegion& region = *active_->region;
  std::vector<ConvertedSphereState> st;
  st.reserve(pc->mls.sampled.size());
  for (std::int32_t b : pc->mls.sampled) st.push_back(sphereState(b));  // before the PBD model changes
  transferConversion(*pc, region, st);
  timers_.convert_prepare_ms += std::max(pc->mls_prepare_ms, pc->pbd_prepare_ms);
  if (pc->mls.rebuild) addConversionTimes(region);
}

// The region's load and the PBD model's run beside each other, or, both preloaded, one after the other.
template <typename T>
void DissectionSimulation<T>::transferConversion(PendingConversion<T>& pc, NodalRegion& region,
                                                 const std::vector<ConvertedSphereState>& st) {
  const auto installPbd = [&] {
    const auto c1 = std::chrono::steady_clock::now();
    installStrokePbd(pc.pbd);
    timers_.convert_pbd_ms += pc.pbd_prepare_ms + msSince(c1);
    timers_.convert_pbd_build_ms += pc.pbd.build_ms;
  };
  if (pc.cut && pc.pbd.preloaded) {
    // Both models are in their spare buffers: what is left is a swap and a state transfer each, shorter than
    // waking a worker for one of them (measured 0.18-0.29 ms of hand-over on the H100 host).
    const auto c1 = std::chrono::steady_clock::now();
    region.apply(pc.mls, st);
    const auto c2 = std::chrono::steady_clock::now();
    installPbd();
    timers_.apply_region_ms += std::chrono::duration<double, std::milli>(c2 - c1).count();
    timers_.apply_pbd_ms += msSince(c2);
  } else if (pc.cut) {
    timers_.convert_wait_ms += convert_worker_.runBeside([&region, &pc, &st] { region.apply(pc.mls, st); }, installPbd);
  } else {
    region.apply(pc.mls, st);
  }
}

// The parts of a conversion that rebuilt the MLS solver, into the frame's timers.
template <typename T>
void DissectionSimulation<T>::addConversionTimes(const NodalRegion& region) {
  timers_.convert_mls_ms += region.lastRebuildMs();
  const NodalRegion::ConversionTimes& ct = region.lastConversionTimes();
  timers_.convert_sample_ms += ct.sample_ms;
  timers_.convert_supports_ms += ct.supports_ms;
  timers_.convert_mls_model_ms += ct.model_ms;
  timers_.convert_mls_setup_ms += ct.setup_ms;
  timers_.convert_mls_build_ms += ct.model_build_ms;
}

template <typename T>
NodalRegionSettings DissectionSimulation<T>::regionSettings() const {
  NodalRegionSettings s = region_;
  s.mls.safety = std::min(1.0, s.mls.safety * mls_safety_scale_);  // the guard's retries (scaleTimeStep)
  return s;
}

// A base sphere's current state from the PBD model (it is still there when it is converted).
template <typename T>
ConvertedSphereState DissectionSimulation<T>::sphereState(std::int32_t b) const {
  ConvertedSphereState s;
  const std::int32_t i = active_->base_to_pbd[std::size_t(b)];
  s.position = Vec3d(state_.positions[std::size_t(i)]);
  s.velocity = Vec3d(state_.velocities[std::size_t(i)]);
  if (std::size_t(i) < state_.rotations.size()) s.rotation = Mat3d(pbd::quatToMatrix(state_.rotations[std::size_t(i)]));
  return s;
}

// While a stroke may be preloading, PBD frames that one grid launch runs (docs/pbd.md, "Grid frame") are launched
// directly: no capture then waits for a worker's load (each stroke model is new anyway). Larger models keep their
// graphs (their direct path is ~170 launches); a capture then waits for a load in progress (deviceCaptureMutex).
template <typename T>
bool DissectionSimulation<T>::directFrameFits(const PbdStepParams<T>& p) const {
  return p.solver == PbdSolverKind::Jacobi && model_.size() <= std::size_t(std::max(0, p.grid_max_particles));
}

// On the worker that planned it: the plan's model into the spare backend (the one before last), while the frame
// goes on with backend_. Only the worker touches spare_backend_ until the plan is installed.
template <typename T>
void DissectionSimulation<T>::preloadStrokePbd(StrokePbdPlan<T>& plan) {
  const std::lock_guard<std::mutex> lock(deviceCaptureMutex());
  if (!spare_backend_) spare_backend_ = makePbdBackend<T>(backend_->kind());
  spare_backend_->setModel(plan.built);
  plan.preloaded = true;
}

// Makes the plan the stroke's PBD model, its spheres at their current positions and velocities.
template <typename T>
void DissectionSimulation<T>::installStrokePbd(StrokePbdPlan<T>& p) {
  ActiveStroke& a = *active_;
  std::vector<Vec3d> x(p.spheres.size()), v(p.spheres.size());
  std::vector<std::int32_t> old_to_new(model_.size(), -1);
  for (std::size_t i = 0; i < p.spheres.size(); ++i) {
    const std::int32_t old = a.base_to_pbd[std::size_t(p.pbd_to_base[i])];
    x[i] = Vec3d(state_.positions[std::size_t(old)]);
    v[i] = Vec3d(state_.velocities[std::size_t(old)]);
    old_to_new[std::size_t(old)] = std::int32_t(i);
  }
  a.base_to_pbd = std::move(p.base_to_pbd);
  a.pbd_to_base = std::move(p.pbd_to_base);
  mouse_.release();  // sphere indices change
  installSpheres(std::move(p.spheres), std::move(p.built), x, v, old_to_new, p.preloaded);
}

// This file's functions for the two precisions makeDissectionSimulation builds.
#define INC_DISSECTION_CONVERSION(T)                                                                                   \
  template StrokePbdPlan<T> planStrokePbd<T>(const ActiveStroke&, const std::vector<SphereRole>&, MetaballPbdOptions); \
  template void DissectionSimulation<T>::launchConversion(std::unique_ptr<PendingConversion<T>>,                       \
                                                          std::vector<std::int32_t>);                                  \
  template void DissectionSimulation<T>::applyConversion();                                                            \
  template void DissectionSimulation<T>::transferConversion(PendingConversion<T>&, NodalRegion&,                       \
                                                            const std::vector<ConvertedSphereState>&);                 \
  template void DissectionSimulation<T>::addConversionTimes(const NodalRegion&);                                       \
  template NodalRegionSettings DissectionSimulation<T>::regionSettings() const;                                        \
  template ConvertedSphereState DissectionSimulation<T>::sphereState(std::int32_t) const;                              \
  template bool DissectionSimulation<T>::directFrameFits(const PbdStepParams<T>&) const;                               \
  template void DissectionSimulation<T>::preloadStrokePbd(StrokePbdPlan<T>&);                                          \
  template void DissectionSimulation<T>::installStrokePbd(StrokePbdPlan<T>&);
INC_DISSECTION_CONVERSION(float)
INC_DISSECTION_CONVERSION(double)
#undef INC_DISSECTION_CONVERSION

}  // namespace inc::dissection
