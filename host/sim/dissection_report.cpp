// The dissection's frame report: stage times, failure, energies and the counters of strokes, cuts and workers.
#include <algorithm>

#include "host/sim/dissection_simulation_impl.h"
#include "model/frame_budget.h"

namespace inc::dissection {

template <typename T>
void DissectionSimulation<T>::reportStages(FrameReport& rep, const FrameOutcome& out) const {
  const MlsFrameStats& mls = out.mls;
  rep.stages = out.pbd.stages;
  rep.stages.push_back({"cut_sweep", timers_.sweep_ms});
  rep.stages.push_back({"cut_convert", timers_.convert_ms});
  rep.stages.push_back({"cut_convert_pbd", timers_.convert_pbd_ms});          // a share of cut_convert
  rep.stages.push_back({"cut_convert_prepare", timers_.convert_prepare_ms});  // on workers; delayed: off the frame
  rep.stages.push_back({"cut_convert_mls", timers_.convert_mls_ms});          // a share of cut_convert
  // The conversion's parts: sampling, then beside the PBD rebuild the supports and the MLS rebuild (model, setup).
  rep.stages.push_back({"cut_convert_sample", timers_.convert_sample_ms});
  rep.stages.push_back({"cut_convert_supports", timers_.convert_supports_ms});
  rep.stages.push_back({"cut_convert_mls_model", timers_.convert_mls_model_ms});
  rep.stages.push_back({"cut_convert_mls_setup", timers_.convert_mls_setup_ms});
  rep.stages.push_back({"cut_convert_mls_build", timers_.convert_mls_build_ms});  // of _mls_model
  rep.stages.push_back({"cut_convert_pbd_build", timers_.convert_pbd_build_ms});  // of cut_convert_pbd
  rep.stages.push_back({"cut_convert_wait", timers_.convert_wait_ms});          // the MLS half outlasting the PBD half
  rep.stages.push_back({"cut_convert_apply", timers_.convert_apply_ms});        // of cut_convert: a delayed one applied
  rep.stages.push_back({"cut_convert_apply_region", timers_.apply_region_ms});  // preloaded: the points' state transfer
  rep.stages.push_back({"cut_convert_apply_pbd", timers_.apply_pbd_ms});  // preloaded: the spheres' state transfer
  rep.stages.push_back({"mls_integrate", mls.ms_integrate});
  rep.stages.push_back({"mls_coupling", mls.ms_coupling});
  rep.stages.push_back({"mls_stress", mls.ms_stress});
  rep.stages.push_back({"mls_forces", mls.ms_forces});
  rep.stages.push_back({"mls_reduce", mls.ms_reduce});
  rep.stages.push_back({"mls_substeps", mls.ms_substeps});
  rep.stages.push_back({"mls_wall", timers_.mls_ms});
  rep.stages.push_back({"coupling_exchange", timers_.exchange_ms});
  rep.stages.push_back({"cut_repack", timers_.repack_ms});
  rep.stages.push_back({"cut_apply", timers_.apply_ms});
  rep.stages.push_back(
      {"cut_apply_wait", timers_.apply_wait_ms});  // of cut_apply: the stroke end's worker (or computing it)
  rep.stages.push_back({"cut_open_wait", timers_.open_wait_ms});  // of cut_apply: a surface opening's, likewise
}

// The first half to go non-finite: the spheres ("pbd"), else the points ("mls_" and their stage).
template <typename T>
void DissectionSimulation<T>::reportFailure(FrameReport& rep, const FrameOutcome& out) const {
  rep.finite = out.pbd.finite && out.mls_finite;
  if (!out.pbd.finite) {
    rep.failure_stage = "pbd";
    rep.failure_particle = out.pbd.failure_particle;
  } else if (!out.mls_finite && out.mls.substeps_needed > 0 && coupled()) {
    // The nodal points' exchange was refused for the frame budget: the need and the limit per frame.
    const NodalRegion& region = *active_->region;
    const int k = scene_.cutting.exchanges_per_frame;
    refuseFrame(rep,
                substepLimitReason("MLS substeps of the cut's " + std::to_string(region.pointCount()) + " nodal points",
                                   out.mls.substeps_needed * k, region.substepLimit() * k, region.substepLimitRule(),
                                   "the material (material.youngs_modulus_pa: softer), the points' spacing "
                                   "(cutting.samples_per_diameter: fewer; geometry.spacing_m or "
                                   "pbd.target_spheres: larger spheres), solver.frame_dt_s (shorter), "
                                   "cutting.mls_substeps_per_exchange"));
  } else if (!out.mls_finite) {
    rep.failure_stage = "mls_" + out.mls.totals.bad_stage;
    rep.failure_particle = out.mls.totals.first_bad;
  }
}

template <typename T>
void DissectionSimulation<T>::report(FrameReport& rep, const MlsFrameStats& mls, int exchanges) const {
  reportEnergies(rep);
  reportStroke(rep, mls, exchanges);
  reportCuts(rep);
  reportWork(rep);
}

// Energies, largest displacement and mass over the spheres and, during a stroke, the nodal points (an interface
// sphere's mass and motion are its points'); the coupling springs' energy counts as elastic.
template <typename T>
void DissectionSimulation<T>::reportEnergies(FrameReport& rep) const {
  double ke = 0, pe = 0, disp = 0, mass = 0;
  const NodalRegion* region = coupled() ? active_->region.get() : nullptr;
  for (std::size_t i = 0; i < model_.size(); ++i) {
    if (region && isKinematic(std::int32_t(i))) continue;  // its mass and motion are its points'
    const Vec3d x(state_.positions[i]), x0(model_.rest_positions[i]), v(state_.velocities[i]);
    ke += 0.5 * double(model_.masses[i]) * norm2(v);
    pe -= double(model_.masses[i]) * dot(scene_.solver.gravity, x - x0);
    disp = std::max(disp, norm(x - x0));
    mass += double(model_.masses[i]);
  }
  double spring = 0.0;
  if (region) {
    const MlsReduction& r = region->lastReduction();
    ke += r.kinetic_energy;
    pe += r.potential_energy;
    rep.elastic_energy = r.elastic_energy;
    disp = std::max(disp, r.max_displacement);
    mass += region->pointMass();
    spring = region->springEnergy();
    rep.elastic_energy += spring;
  }
  rep.kinetic_energy = ke;
  rep.potential_energy = pe;
  rep.max_displacement = disp;
  rep.counters["mass_kg"] = mass;
  rep.counters["coupling_spring_energy_j"] = spring;
}

// The spheres and grasps, and the stroke in progress: its spheres' roles, nodal points, coupling and MLS figures
// (zero without one).
template <typename T>
void DissectionSimulation<T>::reportStroke(FrameReport& rep, const MlsFrameStats& mls, int exchanges) const {
  const NodalRegion* region = coupled() ? active_->region.get() : nullptr;
  std::size_t pending = 0, interface = 0;
  if (active_ && active_->region)
    for (std::size_t b = 0; b < active_->base.size(); ++b) {
      pending += active_->region->role(std::int32_t(b)) == SphereRole::Cut;
      interface += active_->region->role(std::int32_t(b)) == SphereRole::Interface;
    }
  const MlsModelStats* ms = region && region->solver() ? &region->solver()->modelStats() : nullptr;
  rep.counters["spheres"] = double(model_.size());
  rep.counters["cut_spheres_pending"] = double(pending);
  rep.counters["interface_spheres"] = double(interface);
  rep.counters["nodal_points"] = region ? double(region->pointCount()) : 0.0;
  rep.counters["nodal_max_displacement_m"] = region ? region->lastReduction().max_displacement : 0.0;
  rep.counters["coupling_springs"] = region ? double(region->springCount()) : 0.0;
  rep.counters["coupling_exchanges"] = double(exchanges);
  rep.counters["mls_substeps"] = double(mls.substeps);
  rep.counters["mls_isolated_points"] = ms ? double(ms->isolated) : 0.0;
  rep.counters["mls_regularised_points"] = ms ? double(ms->regularised) : 0.0;
  rep.counters["supports_cut"] = region ? double(region->supportsRemoved()) : 0.0;
  int grasped = mouse_.held();
  for (const Grasper& g : graspers_) grasped += int(g.grasped().size());
  rep.counters["grasped"] = double(grasped);
}

// The cuts applied so far and the last one's re-packing and surface split.
template <typename T>
void DissectionSimulation<T>::reportCuts(FrameReport& rep) const {
  rep.counters["cuts_applied"] = double(cuts_done_);
  rep.counters["sphere_components"] = double(sphere_components_);
  rep.counters["links"] = double(spheres_.links.size());
  rep.counters["nodal_points_last_cut"] = double(last_points_);
  rep.counters["spheres_added_last_cut"] = double(last_added_);
  rep.counters["repack_groups"] = double(last_repack_.groups);
  rep.counters["repack_boundary_points"] = double(last_repack_.boundary);
  rep.counters["repack_medial_points"] = double(last_repack_.medial);
  rep.counters["repack_middle_points"] = double(last_repack_.middle);
  rep.counters["repack_packed"] = double(last_repack_.packed);
  rep.counters["repack_merged"] = double(last_repack_.merged);
  rep.counters["repack_spacing_m"] = last_repack_.spacing_max;
  rep.counters["surface_split"] = surface_split_ ? 1.0 : 0.0;
  rep.counters["surface_components"] = double(surface_components_);
  rep.counters["surface_split_failed"] = last_split_failure_.empty() ? 0.0 : 1.0;  // the last applied cut's
}

// The cutting work's times and the workers' states: stroke ends and surface openings in the making or shown.
template <typename T>
void DissectionSimulation<T>::reportWork(FrameReport& rep) const {
  rep.counters["sweep_ms"] = timers_.sweep_ms;
  rep.counters["convert_ms"] = timers_.convert_ms;
  rep.counters["repack_ms"] = timers_.repack_ms;
  rep.counters["cut_apply_ms"] = timers_.apply_ms;
  rep.counters["stroke_end_pending"] = ending_ ? 1.0 : 0.0;
  rep.counters["surface_opened"] = opening_.shown() ? 1.0 : 0.0;  // a stroke's partial opening is shown
  rep.counters["surface_open_pending"] = opening_.inMaking() ? 1.0 : 0.0;
  rep.counters["surface_open_ms"] = opening_.lastWorkerMs();  // the last applied opening's worker time
  rep.counters["surface_open_here"] =
      double(opening_.computedHere());  // openings computed on the frame's thread so far
  rep.counters["stroke_end_worker_ms"] = last_end_.worker_ms;
  rep.counters["stroke_end_here"] = last_end_here_ ? 1.0 : 0.0;  // the last end: its worker given up on
  rep.counters["stroke_end_repack_ms"] = last_end_.repack_ms;
  rep.counters["stroke_end_build_ms"] = last_end_.build_ms;
  rep.counters["stroke_end_split_ms"] = last_end_.split_ms;
  rep.counters["stroke_end_bind_ms"] = last_end_.bind_ms;
}

// This file's members for the two precisions makeDissectionSimulation builds.
#define INC_DISSECTION_REPORT(T)                                                                      \
  template void DissectionSimulation<T>::reportStages(FrameReport&, const FrameOutcome&) const;       \
  template void DissectionSimulation<T>::reportFailure(FrameReport&, const FrameOutcome&) const;      \
  template void DissectionSimulation<T>::report(FrameReport&, const MlsFrameStats&, int) const;       \
  template void DissectionSimulation<T>::reportEnergies(FrameReport&) const;                          \
  template void DissectionSimulation<T>::reportStroke(FrameReport&, const MlsFrameStats&, int) const; \
  template void DissectionSimulation<T>::reportCuts(FrameReport&) const;                              \
  template void DissectionSimulation<T>::reportWork(FrameReport&) const;
INC_DISSECTION_REPORT(float)
INC_DISSECTION_REPORT(double)
#undef INC_DISSECTION_REPORT

}  // namespace inc::dissection
