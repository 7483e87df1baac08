// The dissection's stroke ends: re-packing, surface split and skin binding on workers, applied frames later.
// They start on idle-priority workers when the blade leaves (rest configuration only); the result is applied
// cutting.stroke_end_frames frames later with the state of then.
#include "host/sim/dissection_stroke_end.h"

#include <chrono>
#include <map>

#include "base/elapsed_ms.h"
#include "host/sim/dissection_simulation_impl.h"

namespace inc::dissection {

template <typename T>
void StrokeEndWorkers<T>::start(const std::shared_ptr<PendingStrokeEnd<T>>& e, MetaballPbdOptions opt) {
  if (!worker_.done()) return;  // still on an end given up on (starved): this one is computed when due
  e->on_worker = true;
  // The task holds the pending end (shared): collect may give up on it and go on without it.
  worker_.start([e, split = &split_worker_, opt = std::move(opt), gate = idleWorkerGate()] {
    if (gate) gate();
    e->result = computeStrokeEnd(e->input, *split,
                                 [&e, &opt](const MetaballModel& m) { e->pbd = buildMetaballPbdModel<T>(m, opt); });
  });
}

template <typename T>
StrokeEndOutcome<T> StrokeEndWorkers<T>::collect(PendingStrokeEnd<T>& e, double patience_ms, BackgroundTask& beside,
                                                 const MetaballPbdOptions& opt) {
  StrokeEndOutcome<T> out;
  bool here = !e.on_worker;
  if (e.on_worker && !worker_.done()) {  // the frames ran out before the workers: normal priority now
    worker_.boost();
    split_worker_.boost();
    here = !worker_.waitFor(patience_ms);
  }
  out.computed_here = here;
  if (here) {  // the worker's copy of the result is left to it (it finishes in the background)
    out.result =
        computeStrokeEnd(e.input, beside, [&](const MetaballModel& m) { out.pbd = buildMetaballPbdModel<T>(m, opt); });
    return out;
  }
  worker_.wait();  // rethrows what the worker threw
  out.result = std::move(e.result);
  out.pbd = std::move(e.pbd);
  return out;
}

template class StrokeEndWorkers<float>;
template class StrokeEndWorkers<double>;

// The blade leaves. Every heavy part of a stroke's end works in the rest configuration (Algorithm 1 on the
// points' rest positions, the new PBD model's build, the surface split, the skin binding: host/cut/cut_stroke_end.h),
// so it starts now on a worker and is applied cutting.stroke_end_frames frames later, the nodal points and
// spheres simulated meanwhile as during the stroke; the state transfer (applyStrokeEnd) reads the state then.
// A fixed frame count, not "when the worker is done", keeps runs deterministic. 0 frames: applied now.
template <typename T>
void DissectionSimulation<T>::endStroke() {
  applyConversion();  // the stroke's last strip
  ActiveStroke& a = *active_;
  if (a.swept.empty()) {
    ++cuts_done_;
    active_.reset();
    return;
  }
  auto e = std::make_shared<PendingStrokeEnd<T>>();
  e->input = strokeEndInput(a);
  e->frames_left = scene_.cutting.stroke_end_frames;
  ending_ = e;
  if (e->frames_left <= 0) {  // due now: computed on this thread (applyStrokeEnd), no worker
    applyStrokeEnd();
    return;
  }
  end_workers_.start(e, pbdOptions({}, false));
}

// Everything the stroke's end reads, fixed when the blade leaves.
template <typename T>
StrokeEndInput DissectionSimulation<T>::strokeEndInput(const ActiveStroke& a) const {
  StrokeEndInput in;
  in.repack = a.region && a.region->active();
  // The kept model is the stroke's PBD model's spheres in the same order, so a grasp on one stays valid.
  std::vector<std::int32_t> base_to_kept;
  in.kept = uncutSpheres(a.base, a.region ? &a.region->roles() : nullptr, base_to_kept);
  if (in.repack) in.points = a.region->repackPoints();
  in.settings.boundary_offset = scene_.cutting.repack_boundary_offset;
  in.settings.spacing_factor = scene_.cutting.repack_spacing_factor;
  in.settings.sphere_budget = scene_.cutting.repack_sphere_budget;
  in.settings.reference_mass = reference_mass_;
  in.settings.max_radius = 1.5 * reference_radius_;
  in.cuts = earlier_cuts_;
  in.cuts.push_back(a.swept);
  in.surface = surface_;
  in.skin_k = 4;
  in.file = scene_.file;
  in.interactive = a.scripted < 0;
  return in;
}

// The stroke end computed by the worker (or here, StrokeEndWorkers::collect), applied with the state of now. The
// nodal points go back to zero.
template <typename T>
void DissectionSimulation<T>::applyStrokeEnd() {
  const auto c0 = std::chrono::steady_clock::now();
  opening_.discard();  // the stroke's end replaces whatever opening there is
  std::shared_ptr<PendingStrokeEnd<T>> e = std::move(ending_);
  StrokeEndOutcome<T> end =
      end_workers_.collect(*e, workerPatienceMs(last_end_.worker_ms), convert_worker_, pbdOptions({}, false));
  last_end_here_ = end.computed_here && e->on_worker;
  timers_.apply_wait_ms += msSince(c0);
  std::unique_ptr<ActiveStroke> a = std::move(active_);
  StrokeEndResult& r = end.result;
  ++cuts_done_;
  last_points_ = 0;
  last_added_ = 0;
  if (r.repacked) installRepackedSpheres(*a, e->input, r, end.pbd);
  if (r.split) installCutSurface(r);
  recordCut(*a, r);
}

// The re-packed model with the state of now: interface spheres return to PBD at their eq. 13 position, every new
// sphere takes the mass-weighted mean displacement and velocity of the points it took, the other spheres keep
// theirs.
template <typename T>
void DissectionSimulation<T>::installRepackedSpheres(ActiveStroke& a, const StrokeEndInput& in, StrokeEndResult& r,
                                                     PbdModel<T>& built) {
  last_points_ = a.region->pointCount();
  const NodalRegionFinal fin = a.region->finish(false);
  std::map<std::int32_t, std::size_t> iface;
  for (std::size_t k = 0; k < fin.interface_ids.size(); ++k) iface[fin.interface_ids[k]] = k;
  std::vector<Vec3d> x, v;
  std::vector<std::int32_t> old_to_new(model_.size(), -1);
  for (std::size_t b = 0; b < a.base.size(); ++b) {
    if (a.region->role(std::int32_t(b)) == SphereRole::Cut) continue;
    const std::int32_t pbd = a.base_to_pbd[b];
    old_to_new[std::size_t(pbd)] = std::int32_t(x.size());
    const auto it = iface.find(std::int32_t(b));
    if (it != iface.end()) {
      x.push_back(fin.interface_position[it->second]);  // eq. 13
      v.push_back(fin.interface_velocity[it->second]);
    } else {
      x.push_back(Vec3d(state_.positions[std::size_t(pbd)]));
      v.push_back(Vec3d(state_.velocities[std::size_t(pbd)]));
    }
  }
  const RepackResult& rp = r.repack;
  std::vector<Vec3d> nu(rp.centres.size()), nv(rp.centres.size());
  std::vector<double> nm(rp.centres.size(), 0.0);
  for (std::size_t i = 0; i < in.points.size(); ++i) {
    if (in.points.context[i]) continue;
    const std::size_t s = std::size_t(rp.owner[i]);
    nu[s] += fin.displacement[i] * in.points.mass[i];
    nv[s] += fin.velocity[i] * in.points.mass[i];
    nm[s] += in.points.mass[i];
  }
  for (std::size_t s = 0; s < rp.centres.size(); ++s) {
    x.push_back(rp.centres[s] + nu[s] * (1.0 / nm[s]));
    v.push_back(nv[s] * (1.0 / nm[s]));
  }
  last_repack_ = rp;
  last_added_ = rp.centres.size();
  timers_.repack_ms += r.repack_ms;
  installSpheres(std::move(r.spheres), std::move(built), x, v, old_to_new);
}

// The split surface replaces the old.
template <typename T>
void DissectionSimulation<T>::installCutSurface(StrokeEndResult& r) {
  surface_ = std::make_shared<const CutSurfaceState>(std::move(r.surface));
  surface_components_ = r.surface_components;  // from the split's own output check: no second analysis
  rest_surface_ = surface_->mesh;
  wall_flags_ = surface_->wall;
  surface_split_ = true;
}

// The stroke joins the earlier cuts; the new skin replaces the old; the end's figures for the report.
template <typename T>
void DissectionSimulation<T>::recordCut(ActiveStroke& a, StrokeEndResult& r) {
  earlier_cuts_.push_back(std::move(a.swept));
  skin_ = skinSlots(std::move(r.skin));
  skin_rest_centres_ = spheres_.rest_centers;
  sphere_components_ = r.sphere_components;
  last_split_failure_ = r.split_failure;
  last_end_ = {r.total_ms, r.repack_ms, r.build_ms, r.split_ms, r.bind_ms};
}

// This file's members for the two precisions makeDissectionSimulation builds.
#define INC_DISSECTION_STROKE_END(T)                                                                  \
  template void DissectionSimulation<T>::endStroke();                                                 \
  template StrokeEndInput DissectionSimulation<T>::strokeEndInput(const ActiveStroke&) const;         \
  template void DissectionSimulation<T>::applyStrokeEnd();                                            \
  template void DissectionSimulation<T>::installRepackedSpheres(ActiveStroke&, const StrokeEndInput&, \
                                                                StrokeEndResult&, PbdModel<T>&);      \
  template void DissectionSimulation<T>::installCutSurface(StrokeEndResult&);                         \
  template void DissectionSimulation<T>::recordCut(ActiveStroke&, StrokeEndResult&);
INC_DISSECTION_STROKE_END(float)
INC_DISSECTION_STROKE_END(double)
#undef INC_DISSECTION_STROKE_END

}  // namespace inc::dissection
