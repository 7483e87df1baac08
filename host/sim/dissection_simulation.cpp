// DissectionSimulation's set-up, frame order, PBD model and SimulationModel interface (the other concerns: impl.h).
// PBD metaballs cut by scalpel strokes; while the blade is in the tissue the cut spheres are MLS nodal points coupled
// both ways with the spheres (section 5.2-5.3), re-packed by Algorithm 1 when it leaves.
#include "host/sim/dissection_simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <mutex>

#include "base/elapsed_ms.h"
#include "host/assembly/organ_shapes.h"
#include "host/assembly/scene_surface.h"
#include "host/compiled/scene_colliders.h"
#include "host/sim/dissection_scene_checks.h"
#include "host/sim/dissection_simulation_impl.h"
#include "host/sim/metaball_simulation.h"
#include "host/sim/mls_simulation.h"
#include "host/sim/pbd_organ_settings.h"
#include "host/sim/pbd_render_layers.h"
#include "model/device_capture_lock.h"
#include "model/frame_budget.h"
#include "model/input_error.h"

namespace inc::dissection {

// --- Set-up -----------------------------------------------------------------------------------------------

template <typename T>
DissectionSimulation<T>::DissectionSimulation(const CompiledScene& scene, BackendKind backend) : scene_(scene) {
  checkDissectionScene(scene);
  readTools();
  setPbdParams();
  buildOrgan();
  checkFixedSubstepsFit(scene_.solver.substeps, spheres_.size(), scene_.solver.max_substeps, scene_.file);
  backend_ = makePbdBackend<T>(backend);
  setRegionSettings();
  checkFixedMlsSubsteps(scene_, spheres_, region_.mls.material);
  measureReferenceSphere();
  installFirstModel();
}

// Scalpels become scripted strokes (sorted by start, apart in time), graspers and probes act on the spheres.
template <typename T>
void DissectionSimulation<T>::readTools() {
  const std::string& f = scene_.file;
  for (std::size_t k = 0; k < scene_.tools.size(); ++k) {
    const ToolSpec& t = scene_.tools[k];
    const std::string key = "tools[" + std::to_string(k) + "]";
    if (t.kind == "scalpel") {
      if (t.path.size() < 2) throw InputError(f, key + ".path", "a scalpel needs >= 2 keyframes");
      if (!(t.length > 0)) throw InputError(f, key + ".length_m", "must be > 0");
      strokes_.push_back({t, t.path.front().t, t.path.back().t});
    } else if (t.kind == "grasper") {
      if (t.path.empty()) throw InputError(f, key + ".path", "needs at least one keyframe");
      graspers_.emplace_back(t, t.radius + scene_.geometry.spacing, 1.0e-6);
    } else if (t.kind == "probe") {
      if (t.path.empty()) throw InputError(f, key + ".path", "needs at least one keyframe");
      probes_.push_back(t);
    }
  }
  // With models.haptics the blade may come only from a haptic device (applyTool), without a scripted one.
  if (strokes_.empty() && !scene_.models.haptics)
    throw InputError(f, "tools", "cutting needs a tool of kind \"scalpel\"");
  std::stable_sort(strokes_.begin(), strokes_.end(),
                   [](const ScriptedStroke& a, const ScriptedStroke& b) { return a.start < b.start; });
  checkStrokesApart(f, strokes_);
}

template <typename T>
void DissectionSimulation<T>::setPbdParams() {
  params_ = pbdOrganParams<T>(scene_);
  base_substeps_ = scene_.solver.substeps > 0 ? scene_.solver.substeps : 4;
}

// The organ's spheres, its surface and the colliders drawn around it.
template <typename T>
void DissectionSimulation<T>::buildOrgan() {
  spheres_ = buildSceneMetaballs(scene_, &fill_note_);
  checkCollidersClear(scene_, spheres_.rest_centers, "sphere centres");
  collider_mesh_ = colliderMeshAround(scene_.colliders, spheres_.rest_centers);
  rest_surface_ = sceneSurfaceMesh(scene_);
  surface_ = std::make_shared<const CutSurfaceState>(cutSurfaceState(rest_surface_));
}

// The settings every stroke's nodal points are built with (NodalRegion), and whether conversions preload.
template <typename T>
void DissectionSimulation<T>::setRegionSettings() {
  region_.samples_per_diameter = scene_.cutting.samples_per_diameter;
  region_.backend = backend_->kind();  // the nodal points run on the backend the scene asked for
  preload_ = scene_.cutting.conversion_delay_frames > 0 && backend_->kind() == BackendKind::Cuda &&
             !std::getenv("INCISION_NO_PRELOAD");
  region_.precision = sizeof(T) == 8 ? Precision::Float64 : Precision::Float32;
  region_.fixed = scene_.fixed;
  region_.colliders = staticColliders(scene_.colliders);
  region_.stretch_compliance = scene_.pbd.stretch_compliance;
  region_.mls = mlsSolverSettings(scene_);
  region_.max_substeps = scene_.solver.max_substeps;
  region_.exchanges_per_frame = scene_.cutting.exchanges_per_frame;
}

// The organ as first packed: its typical sphere sets the re-packing's budget and radius cap for every cut (a mean
// over re-packed spheres would drift), and its surface bounds where converted spheres put points.
template <typename T>
void DissectionSimulation<T>::measureReferenceSphere() {
  for (std::size_t i = 0; i < spheres_.size(); ++i) {
    reference_mass_ += spheres_.masses[i] / double(spheres_.size());
    reference_radius_ += spheres_.rest_radii[i] / double(spheres_.size());
  }
  tissue_ = std::make_shared<pack::SurfaceDistance>(rest_surface_);
  region_.inside = [tissue = tissue_](const Vec3d& x) { return tissue->insideByRays(x); };
}

template <typename T>
void DissectionSimulation<T>::installFirstModel() {
  std::vector<Vec3d> x(spheres_.rest_centers), v(spheres_.size());
  // The scene's supports must hold the organ as built (after a cut the clamped part may be gone).
  installSpheres(spheres_, buildMetaballPbdModel<T>(spheres_, pbdOptions({}, true)), x, v, {});
  bindSurface();
  surface_components_ = analyzeMesh(rest_surface_).components;  // then each split reports its own
  sphere_components_ = sphereGraphComponents(spheres_);
  saveCheckpoint();
}

// --- The frame ----------------------------------------------------------------------------------------------

template <typename T>
FrameReport DissectionSimulation<T>::advance(double frame_dt) {
  const double t0 = time_, t1 = time_ + frame_dt;
  startFrameTimers();
  applyDueWork(t0);
  takeMouseBlade();
  scriptedStrokes(t0, t1);
  updateGraspers(t0);
  const PbdFrameInput<T> in = frameInput(t0, t1);
  FrameOutcome out;
  FrameReport rep;
  // The frame budget (model/frame_budget.h): the spheres' substeps this frame, refused beyond the limit.
  if (std::string why = pbdRefusal(frame_dt); !why.empty()) {
    refuseFrame(rep, std::move(why));
    return rep;
  }
  if (coupled())
    coupledFrame(frame_dt, in, out);
  else
    pbdFrame(frame_dt, in, out);
  mouse_.frameDone();
  time_ = t1;
  rep.substeps = out.pbd_substeps;
  rep.dt = frame_dt / std::max(1, out.pbd_substeps);
  reportStages(rep, out);
  reportFailure(rep, out);
  report(rep, out.mls, out.exchanges);
  rep.counters["volume_active"] = double(out.pbd.volume_active);  // spheres whose radius volume preservation set
  return rep;
}

// A frame's timers start with what the mouse's strokes spent since the last frame (applyTool).
template <typename T>
void DissectionSimulation<T>::startFrameTimers() {
  timers_ = Timers{};
  timers_.apply_ms = mouse_cut_ms_;
  timers_.convert_ms = mouse_convert_ms_;
  mouse_cut_ms_ = mouse_convert_ms_ = 0.0;
}

// At the frame's start, in this order: a delayed conversion, a surface opening due now (then the next one started),
// a stroke end due now.
template <typename T>
void DissectionSimulation<T>::applyDueWork(double t0) {
  if (converting_ && t0 > converting_->launched_at) {  // delayed from an earlier frame (not this one retried)
    const auto c0 = std::chrono::steady_clock::now();
    applyConversion();
    timers_.convert_apply_ms = msSince(c0);
    timers_.convert_ms += timers_.convert_apply_ms;
  }
  if (opening_.dueAt(t0)) {
    const auto c0 = std::chrono::steady_clock::now();
    timers_.open_wait_ms += opening_.apply();
    timers_.apply_ms += msSince(c0);
  }
  openSurface(t0);
  if (ending_ && --ending_->frames_left <= 0) {
    const auto c0 = std::chrono::steady_clock::now();
    applyStrokeEnd();
    timers_.apply_ms += msSince(c0);
  }
}

// The mouse blade's motion since the last frame is this frame's blade while its stroke is in the tissue.
template <typename T>
void DissectionSimulation<T>::takeMouseBlade() {
  frame_blade_ = FrameBlade{};
  if (active_ && !ending_ && active_->scripted < 0) frame_blade_ = {true, mouse_blade_from_, mouse_blade_to_};
  mouse_blade_from_ = mouse_blade_to_;
}

template <typename T>
PbdFrameInput<T> DissectionSimulation<T>::frameInput(double t0, double t1) const {
  PbdFrameInput<T> in;
  for (const Grasper& g : graspers_) appendGrasperInput(g, t0, t1, in);
  appendProbeInputs(probes_, t0, t1, in);
  appendBladeInput(in);
  appendMouseAttachments(mouse_, in);
  return in;
}

// Why this frame's PBD substeps exceed the frame's limit ("" when they fit): all exchanges' during a stroke.
template <typename T>
std::string DissectionSimulation<T>::pbdRefusal(double frame_dt) const {
  const int per_frame = coupled() ? scene_.cutting.exchanges_per_frame * exchangeParams(frame_dt).substeps
                                  : std::max(1, int(std::ceil(base_substeps_ * substep_scale_ - 1e-9)));
  return pbdSubstepRefusal(per_frame, model_.size(), scene_.solver.max_substeps,
                           std::string(kPbdSubstepKeys) + ", cutting.pbd_substeps_per_exchange");
}

// A frame without nodal points: the PBD spheres alone.
template <typename T>
void DissectionSimulation<T>::pbdFrame(double frame_dt, const PbdFrameInput<T>& in, FrameOutcome& out) {
  PbdStepParams<T> p = params_;
  p.frame_dt = T(frame_dt);
  p.substeps = out.pbd_substeps = std::max(1, int(std::ceil(base_substeps_ * substep_scale_ - 1e-9)));
  if (preload_ && active_ && directFrameFits(p)) p.use_graph = false;  // a worker may be loading the next model
  out.pbd = backend_->advanceFrame(p, in);
  backend_->getState(state_);
}

template <typename T>
void DissectionSimulation<T>::updateGraspers(double t0) {
  for (Grasper& g : graspers_) {
    if (g.holding() && t0 >= g.releaseTime()) g.release();
    if (!g.holding() && !g.finished() && t0 >= g.closeTime() && t0 < g.releaseTime()) {
      std::vector<Vec3d> c(model_.size());
      std::vector<double> r(model_.size());
      std::vector<std::uint8_t> movable(model_.size());
      for (std::size_t i = 0; i < model_.size(); ++i) {
        c[i] = Vec3d(state_.positions[i]);
        r[i] = double(state_.radii[i]);
        movable[i] = model_.inv_mass[i] > T(0) && !isKinematic(std::int32_t(i)) ? 1 : 0;
      }
      g.grasp(toolPoseAt(g.tool(), t0).position, c, r, movable);
    }
  }
}

template <typename T>
void DissectionSimulation<T>::appendBladeInput(PbdFrameInput<T>& in) const {
  if (!bladeContact()) return;
  in.volume_tools = int(in.tools_to.size());  // the tools before the blade: it is a contact, not a squeeze
  const auto capsule = [&](const BladePose& p) {
    pbd::CapsuleCollider<T> c;
    c.a = Vec3<T>(p.base);
    c.b = Vec3<T>(p.tip);
    c.radius = T(scene_.cutting.blade_radius_m);
    c.friction = T(scene_.cutting.blade_friction);  // the spheres slide on the blade as its points do
    return c;
  };
  in.tools_from.push_back(capsule(frame_blade_.from));
  in.tools_to.push_back(capsule(frame_blade_.to));
}

// --- Checkpoints and the guard's time step ------------------------------------------------------------------

template <typename T>
void DissectionSimulation<T>::saveCheckpoint() {
  saved_state_ = state_;
  saved_time_ = time_;
  saved_version_ = version_;
  saved_graspers_ = graspers_;
  saved_frames_left_ = ending_ ? ending_->frames_left : -1;
  opening_.saveCheckpoint();
  if (active_ && active_->region) active_->region->saveCheckpoint();
}

template <typename T>
void DissectionSimulation<T>::restoreCheckpoint() {
  // A checkpoint taken before a topology change (a conversion or a re-pack) cannot be restored after it; the
  // guard then retries from the current state, which the runner treats like a restored one.
  time_ = saved_time_;
  if (saved_version_ == version_) {
    state_ = saved_state_;
    graspers_ = saved_graspers_;
    backend_->setState(state_);
    if (active_ && active_->region) active_->region->restoreCheckpoint();
    if (ending_ && saved_frames_left_ >= 0) ending_->frames_left = saved_frames_left_;  // the retried frame counts once
    opening_.restoreCheckpoint();
  }
}

template <typename T>
void DissectionSimulation<T>::scaleTimeStep(double factor) {
  if (!(factor > 0) || !std::isfinite(factor)) return;
  substep_scale_ /= factor;
  mls_safety_scale_ *= factor;
  if (active_ && active_->region) active_->region->scaleSafety(factor);
}

// --- What the runner and the viewer read ------------------------------------------------------------------

template <typename T>
void DissectionSimulation<T>::currentPositions(std::vector<Vec3d>& out) const {
  out.resize(state_.positions.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3d(state_.positions[i]);
}

template <typename T>
MemoryReport DissectionSimulation<T>::memory() const {
  MemoryReport m = backend_->memory();
  {
    const std::lock_guard<std::mutex> lock(deviceCaptureMutex());  // a worker may be loading it
    if (spare_backend_) m.device_bytes += spare_backend_->memory().device_bytes;
  }
  m.host_bytes += model_.size() * (sizeof(Vec3<T>) * 3 + sizeof(T) * 4) +
                  rest_surface_.vertices.size() * sizeof(Vec3d) + rest_surface_.triangles.size() * 12;
  if (active_ && active_->region && active_->region->solver()) {
    const MemoryReport r = active_->region->solver()->memory();
    m.host_bytes += r.host_bytes;
    m.device_bytes += r.device_bytes;
  }
  return m;
}

// The viewer's layers: spheres, fixed spheres, the spheres the graspers and the mouse hold
// (host/sim/pbd_render_layers.h), the swept surfaces of the applied cuts and of the stroke in progress carried by the
// spheres (host/sim/dissection_render_layers.h), and, while a stroke is in the tissue, the nodal points where the
// MLS solver has them now (they go back to zero when the stroke ends).
template <typename T>
void DissectionSimulation<T>::renderLayers(RenderLayers& out) const {
  out = RenderLayers{};
  out.colliders = collider_mesh_;
  appendPbdSpheres(state_, out);
  appendPbdFixed(model_, state_, out);
  // The held spheres as the frame's input is assembled: scripted graspers first, then the mouse's others; a
  // kinematic (interface) sphere is held by its points, not by a grasp (coupledFrame skips its attachment).
  const auto held = [&](const PbdFrameInput<T>& in, std::size_t from) {
    PbdFrameInput<T> o;
    for (std::size_t k = from; k < in.attach_ids.size(); ++k) {
      if (coupled() && isKinematic(in.attach_ids[k])) continue;
      o.attach_ids.push_back(in.attach_ids[k]);
      o.attach_from.push_back(in.attach_from[k]);
      o.attach_to.push_back(in.attach_to[k]);
      o.attach_compliance.push_back(in.attach_compliance[k]);
    }
    return o;
  };
  PbdFrameInput<T> all;
  for (const Grasper& g : graspers_) {
    if (!g.holding()) continue;
    const Vec3d tip = toolPoseAt(g.tool(), time_).position;
    PbdFrameInput<T> one;
    g.appendAttachments(tip, tip, one);
    appendAttachmentLayers(held(one, 0), state_, params_.xpbd, tip, out);
    g.appendAttachments(tip, tip, all);
  }
  const std::size_t scripted = all.attach_ids.size();
  appendMouseAttachments(mouse_, all);
  appendAttachmentLayers(held(all, scripted), state_, params_.xpbd, mouse_.tip(), out);
  std::vector<const SweptSurface*> swept = earlierCuts();
  if (active_) swept.push_back(&active_->swept);
  cut_layers_.update(swept, spheres_);
  cut_layers_.apply(out.sphere_centres, out);
  if (coupled() && active_->region->solver()) active_->region->solver()->positions(out.nodal_points);
}

// Grasp & drag (host/sim/interactive_tool.h) and the mouse scalpel (mouseStroke). A conversion changes the sphere
// indices, so it releases any grasp.
template <typename T>
ToolResult DissectionSimulation<T>::applyTool(const ToolEvent& e) {
  std::vector<Vec3d> x(model_.size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = Vec3d(state_.positions[i]);
  if (e.kind == ToolKind::Grasp) {
    std::vector<double> r(model_.size());
    std::vector<std::uint8_t> movable(model_.size());
    for (std::size_t i = 0; i < r.size(); ++i) {
      r[i] = double(state_.radii[i]);
      movable[i] = model_.inv_mass[i] > T(0) && !isKinematic(std::int32_t(i)) ? 1 : 0;
    }
    return mouse_.apply(e, x, r, movable);
  }
  ToolResult res;
  res.supported = true;
  mouseStroke(e, x, res);
  res.grasped = mouse_.held();
  return res;
}

// --- The PBD model ------------------------------------------------------------------------------------------

// The PBD model's build options for this scene (pure: a worker may build with them).
template <typename T>
MetaballPbdOptions DissectionSimulation<T>::pbdOptions(std::vector<double> known_cell_volumes,
                                                       bool require_fixed_held) const {
  MetaballPbdOptions opt = pbdOrganOptions(scene_);
  if (!scene_.colliders.empty())
    opt.surface_depth = [t = tissue_](const Vec3d& x) { return -t->signedDistance(x).distance; };
  opt.require_fixed_held = require_fixed_held;
  opt.coloring = params_.solver == PbdSolverKind::GaussSeidel;  // Jacobi never reads it (a rebuild per conversion)
  opt.known_cell_volumes = std::move(known_cell_volumes);
  return opt;
}

// Makes `built` (the PBD model of `m`) the backend's model with the given positions and velocities; old_to_new
// maps the previous PBD indices (grasps follow their spheres).
template <typename T>
void DissectionSimulation<T>::installSpheres(MetaballModel m, PbdModel<T> built, const std::vector<Vec3d>& x,
                                             const std::vector<Vec3d>& v, const std::vector<std::int32_t>& old_to_new,
                                             bool preloaded) {
  spheres_ = std::move(m);
  model_ = std::move(built);
  if (preloaded)
    std::swap(backend_, spare_backend_);  // loaded on a worker; the current one becomes the next spare
  else
    backend_->setModel(model_);
  state_ = pbdRestState(model_);  // what setModel starts it in (no download)
  for (std::size_t i = 0; i < spheres_.size(); ++i) {
    if (model_.inv_mass[i] == T(0)) continue;  // fixed spheres stay at rest
    state_.positions[i] = Vec3<T>(x[i]);
    state_.velocities[i] = Vec3<T>(v[i]);
  }
  backend_->setState(state_);
  for (Grasper& g : graspers_) g.remap(old_to_new);
  ++version_;
}

template class DissectionSimulation<float>;
template class DissectionSimulation<double>;

}  // namespace inc::dissection

namespace inc {

std::unique_ptr<SimulationModel> makeDissectionSimulation(const CompiledScene& scene, BackendKind backend,
                                                          Precision precision) {
  if (precision == Precision::Float64)
    return std::make_unique<dissection::DissectionSimulation<double>>(scene, backend);
  return std::make_unique<dissection::DissectionSimulation<float>>(scene, backend);
}

}  // namespace inc
