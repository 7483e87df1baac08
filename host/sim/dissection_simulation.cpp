// DissectionSimulation: PBD metaballs cut by scalpel strokes; while the blade is in the tissue the cut spheres are MLS
// nodal points coupled both ways with the spheres (section 5.2-5.3), re-packed by Algorithm 1 when it leaves.
#include "host/sim/dissection_simulation.h"
#include "host/assembly/mls_model_build.h"
#include "host/backends/solver_factory.h"
#include "host/scene/scene_colliders.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <mutex>

#include "base/background_task.h"
#include "host/cut/cut_nodal_points.h"
#include "host/cut/cut_nodal_region.h"
#include "host/cut/cut_repack.h"
#include "host/cut/cut_stroke_end.h"
#include "host/cut/cut_surface_state.h"
#include "host/cut/cut_swept_surface.h"
#include "model/device_capture_lock.h"
#include "host/sim/dissection_render_layers.h"
#include "base/elapsed_ms.h"
#include "host/sim/grasper.h"
#include "model/input_error.h"
#include "host/sim/interactive_tool.h"
#include "host/assembly/metaball_pack_bvh.h"
#include "host/sim/metaball_simulation.h"
#include "host/assembly/organ_shapes.h"
#include "host/assembly/pbd_builders.h"
#include "model/pbd_model.h"
#include "host/sim/pbd_render_layers.h"
#include "host/assembly/skin_binding.h"
#include "physics/mls_integrate.h"
#include "physics/pbd_block.h"
#include "physics/pbd_rotation.h"

namespace inc {

namespace {


// A scripted stroke: one scalpel tool, cutting from its first keyframe's time to its last.
struct ScriptedStroke {
  ToolSpec tool;
  double start = 0, end = 0;  // s
  bool begun = false, done = false;
};

// The cut in progress: the model when it began (base indices), its swept surface, its nodal points, and where
// each base sphere sits in the PBD model now (-1: converted into points and removed).
struct ActiveStroke {
  MetaballModel base;
  SweptSurface swept;
  std::unique_ptr<NodalRegion> region;
  std::vector<std::int32_t> base_to_pbd, pbd_to_base;
  std::vector<double> base_cell_volume;  // the base PBD model's rest cell volumes (empty: volume preservation off)
  std::vector<double> base_contact_inset;  // the base PBD model's contact insets (empty: the scene has no colliders)
  int scripted = -1;  // index into the scripted strokes, -1: the mouse's
  std::size_t opened_triangles = 0;  // swept triangles the last surface opening was started with
};

void addStages(std::vector<StageTime>& into, const std::vector<StageTime>& add) {
  for (const StageTime& s : add) {
    auto it = std::find_if(into.begin(), into.end(), [&](const StageTime& t) { return t.stage == s.stage; });
    if (it == into.end())
      into.push_back(s);
    else
      it->ms += s.ms;
  }
}

template <typename T>
class DissectionSimulation final : public SimulationModel {
 public:
  DissectionSimulation(const Scene& scene, BackendKind backend) : scene_(scene) {
    const std::string& f = scene.file;
    if (!scene.models.cutting) throw InputError(f, "models.cutting", "the dissection model needs cutting: true");
    if (!scene.models.pbd_metaballs) throw InputError(f, "models.pbd_metaballs", "cutting needs the PBD metaball organ");
    if (scene.pbd.iterations < 1) throw InputError(f, "pbd.iterations", "must be >= 1");
    validateCutting(scene);
    for (std::size_t k = 0; k < scene.tools.size(); ++k) {
      const ToolSpec& t = scene.tools[k];
      const std::string key = "tools[" + std::to_string(k) + "]";
      if (t.kind == "scalpel") {
        if (t.path.size() < 2) throw InputError(f, key + ".path", "a scalpel needs >= 2 keyframes");
        if (!(t.length > 0)) throw InputError(f, key + ".length_m", "must be > 0");
        strokes_.push_back({t, t.path.front().t, t.path.back().t});
      } else if (t.kind == "grasper") {
        if (t.path.empty()) throw InputError(f, key + ".path", "needs at least one keyframe");
        graspers_.emplace_back(t, t.radius + scene.geometry.spacing, 1.0e-6);
      } else if (t.kind == "probe") {
        if (t.path.empty()) throw InputError(f, key + ".path", "needs at least one keyframe");
        probes_.push_back(t);
      }
    }
    // With models.haptics the blade may come only from a haptic device (applyTool), without a scripted one.
    if (strokes_.empty() && !scene.models.haptics) throw InputError(f, "tools", "cutting needs a tool of kind \"scalpel\"");
    // Several scalpels are several strokes, one after the other (a stroke is re-packed before the next begins).
    std::stable_sort(strokes_.begin(), strokes_.end(),
                     [](const ScriptedStroke& a, const ScriptedStroke& b) { return a.start < b.start; });
    for (std::size_t k = 1; k < strokes_.size(); ++k)
      if (strokes_[k].start < strokes_[k - 1].end)
        throw InputError(f, "tools", "scalpel \"" + strokes_[k].tool.name + "\" starts at t = " +
                                         std::to_string(strokes_[k].start) + " s, before scalpel \"" +
                                         strokes_[k - 1].tool.name + "\" leaves the tissue at t = " +
                                         std::to_string(strokes_[k - 1].end) + " s: strokes must not overlap");
    params_.solver = parsePbdSolver(scene.pbd.solver, f, "pbd.solver");
    params_.iterations = scene.pbd.iterations;
    params_.chebyshev_rho = T(checkChebyshevRho(scene.pbd.chebyshev_rho, params_.solver, f, "pbd.chebyshev_rho"));
    // CUDA single-block fused frame: measured on an H100 (docs/BENCHMARKS.md) it beats per-phase launches for
    // Gauss-Seidel up to thousands of spheres, but for Jacobi only below ~300 spheres; on sm_90 Jacobi models of up
    // to cluster_max_particles run the thread-block cluster frame instead (faster still, docs/pbd.md).
    params_.fused_max_particles = params_.solver == PbdSolverKind::Jacobi ? 256 : 4096;
    params_.xpbd = scene.pbd.xpbd;
    params_.gravity = Vec3<T>(scene.solver.gravity);
    params_.damping = T(scene.material.damping);
    params_.volume_preservation = scene.pbd.volume_preservation;
    params_.volume_influence = T(2.0 * scene.geometry.spacing);
    base_substeps_ = scene.solver.substeps > 0 ? scene.solver.substeps : 4;
    spheres_ = buildSceneMetaballs(scene);
    checkCollidersClear(scene, spheres_.rest_centers, "sphere centres");
    collider_mesh_ = colliderMeshAround(scene.colliders, spheres_.rest_centers);
    rest_surface_ = sceneSurfaceMesh(scene);
    surface_ = std::make_shared<const CutSurfaceState>(cutSurfaceState(rest_surface_));
    backend_ = makePbdBackend<T>(backend);
    region_.samples_per_diameter = scene.cutting.samples_per_diameter;
    region_.backend = backend_->kind();  // the nodal points run on the backend the scene asked for
    preload_ = scene.cutting.conversion_delay_frames > 0 && backend_->kind() == BackendKind::Cuda &&
               !std::getenv("INCISION_NO_PRELOAD");
    region_.precision = sizeof(T) == 8 ? Precision::Float64 : Precision::Float32;
    region_.fixed = scene.fixed;
    region_.colliders = staticColliders(scene.colliders);
    region_.youngs_modulus = scene.material.youngs_modulus;
    region_.stretch_compliance = scene.pbd.stretch_compliance;
    MlsBuildInput& m = region_.mls;
    m.source = f;
    m.support_factor = scene.mls.support_factor;
    m.condition_limit = scene.mls.condition_limit;
    m.material.youngs_modulus = scene.material.youngs_modulus;
    m.material.poisson_ratio = scene.material.poisson_ratio;
    m.material.density = scene.material.density;
    m.material.damping = scene.material.damping;
    m.material.volume_preservation = scene.mls.volume_preservation;
    m.material.volume_stiffness = scene.mls.volume_stiffness;
    m.gravity = scene.solver.gravity;
    m.safety = scene.solver.safety;
    checkFixedMlsSubsteps();
    // The organ as first packed: its typical sphere sets the re-packing's budget and radius cap for every cut
    // (a mean over re-packed spheres would drift), and its surface bounds where converted spheres put points.
    for (std::size_t i = 0; i < spheres_.size(); ++i) {
      reference_mass_ += spheres_.masses[i] / double(spheres_.size());
      reference_radius_ += spheres_.rest_radii[i] / double(spheres_.size());
    }
    tissue_ = std::make_shared<pack::SurfaceDistance>(rest_surface_);
    region_.inside = [tissue = tissue_](const Vec3d& x) { return tissue->insideByRays(x); };
    std::vector<Vec3d> x(spheres_.rest_centers), v(spheres_.size());
    // The scene's supports must hold the organ as built (after a cut the clamped part may be gone).
    installSpheres(spheres_, buildMetaballPbdModel<T>(spheres_, pbdOptions({}, true)), x, v, {});
    bindSurface();
    surface_components_ = analyzeMesh(rest_surface_).components;  // then each split reports its own
    sphere_components_ = sphereGraphComponents(spheres_);
    saveCheckpoint();
  }

  std::string name() const override { return "dissection"; }
  BackendKind backend() const override { return backend_->kind(); }
  std::size_t particleCount() const override { return model_.size(); }

  FrameReport advance(double frame_dt) override {
    FrameReport rep;
    const double t0 = time_, t1 = time_ + frame_dt;
    timers_ = Timers{};
    timers_.apply_ms = mouse_cut_ms_;
    timers_.convert_ms = mouse_convert_ms_;
    mouse_cut_ms_ = mouse_convert_ms_ = 0.0;
    if (converting_ && t0 > converting_->launched_at) {  // delayed from an earlier frame (not this one retried)
      const auto c0 = std::chrono::steady_clock::now();
      applyConversion();
      timers_.convert_apply_ms = msSince(c0);
      timers_.convert_ms += timers_.convert_apply_ms;
    }
    if (opening_ && t0 > opening_->launched_at && --opening_->frames_left <= 0) {
      const auto c0 = std::chrono::steady_clock::now();
      applyOpening();
      timers_.apply_ms += msSince(c0);
    }
    openSurface(t0);
    if (ending_ && --ending_->frames_left <= 0) {
      const auto c0 = std::chrono::steady_clock::now();
      applyStrokeEnd();
      timers_.apply_ms += msSince(c0);
    }
    frame_blade_ = FrameBlade{};
    if (active_ && !ending_ && active_->scripted < 0) frame_blade_ = {true, mouse_blade_from_, mouse_blade_to_};
    mouse_blade_from_ = mouse_blade_to_;
    scriptedStrokes(t0, t1);
    updateGraspers(t0);
    PbdFrameInput<T> in;
    for (const Grasper& g : graspers_) appendGrasperInput(g, t0, t1, in);
    appendProbeInputs(probes_, t0, t1, in);
    appendBladeInput(in);
    appendMouseAttachments(mouse_, in);
    PbdFrameStats st;
    MlsFrameStats mls;
    int exchanges = 0, pbd_substeps = 0;
    bool mls_finite = true;
    if (coupled()) {
      coupledFrame(frame_dt, in, st, mls, mls_finite, exchanges, pbd_substeps);
    } else {
      PbdStepParams<T> p = params_;
      p.frame_dt = T(frame_dt);
      p.substeps = pbd_substeps = std::max(1, int(std::ceil(base_substeps_ * substep_scale_ - 1e-9)));
      if (preload_ && active_ && directFrameFits(p)) p.use_graph = false;  // a worker may be loading the next model
      st = backend_->advanceFrame(p, in);
      backend_->getState(state_);
    }
    mouse_.frameDone();
    time_ = t1;
    rep.substeps = pbd_substeps;
    rep.dt = frame_dt / std::max(1, pbd_substeps);
    rep.stages = st.stages;
    rep.stages.push_back({"cut_sweep", timers_.sweep_ms});
    rep.stages.push_back({"cut_convert", timers_.convert_ms});
    rep.stages.push_back({"cut_convert_pbd", timers_.convert_pbd_ms});  // a share of cut_convert
    rep.stages.push_back({"cut_convert_prepare", timers_.convert_prepare_ms});  // on workers; delayed: off the frame
    rep.stages.push_back({"cut_convert_mls", timers_.convert_mls_ms});  // a share of cut_convert
    // The conversion's parts: sampling, then beside the PBD rebuild the supports and the MLS rebuild (model, setup).
    rep.stages.push_back({"cut_convert_sample", timers_.convert_sample_ms});
    rep.stages.push_back({"cut_convert_supports", timers_.convert_supports_ms});
    rep.stages.push_back({"cut_convert_mls_model", timers_.convert_mls_model_ms});
    rep.stages.push_back({"cut_convert_mls_setup", timers_.convert_mls_setup_ms});
    rep.stages.push_back({"cut_convert_mls_build", timers_.convert_mls_build_ms});  // of _mls_model
    rep.stages.push_back({"cut_convert_pbd_build", timers_.convert_pbd_build_ms});  // of cut_convert_pbd
    rep.stages.push_back({"cut_convert_wait", timers_.convert_wait_ms});  // the MLS half outlasting the PBD half
    rep.stages.push_back({"cut_convert_apply", timers_.convert_apply_ms});  // of cut_convert: a delayed one applied
    rep.stages.push_back({"cut_convert_apply_region", timers_.apply_region_ms});  // preloaded: the points' state transfer
    rep.stages.push_back({"cut_convert_apply_pbd", timers_.apply_pbd_ms});        // preloaded: the spheres' state transfer
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
    rep.stages.push_back({"cut_apply_wait", timers_.apply_wait_ms});  // of cut_apply: the stroke end's worker (or computing it)
    rep.stages.push_back({"cut_open_wait", timers_.open_wait_ms});    // of cut_apply: a surface opening's, likewise
    rep.finite = st.finite && mls_finite;
    if (!st.finite) {
      rep.failure_stage = "pbd";
      rep.failure_particle = st.failure_particle;
    } else if (!mls_finite) {
      rep.failure_stage = "mls_" + mls.totals.bad_stage;
      rep.failure_particle = mls.totals.first_bad;
    }
    report(rep, mls, exchanges);
    rep.counters["volume_active"] = double(st.volume_active);  // spheres whose radius volume preservation set
    return rep;
  }

  void saveCheckpoint() override {
    saved_state_ = state_;
    saved_time_ = time_;
    saved_version_ = version_;
    saved_graspers_ = graspers_;
    saved_frames_left_ = ending_ ? ending_->frames_left : -1;
    saved_open_frames_left_ = opening_ ? opening_->frames_left : -1;
    if (active_ && active_->region) active_->region->saveCheckpoint();
  }
  void restoreCheckpoint() override {
    // A checkpoint taken before a topology change (a conversion or a re-pack) cannot be restored after it; the
    // guard then retries from the current state, which the runner treats like a restored one.
    time_ = saved_time_;
    if (saved_version_ == version_) {
      state_ = saved_state_;
      graspers_ = saved_graspers_;
      backend_->setState(state_);
      if (active_ && active_->region) active_->region->restoreCheckpoint();
      if (ending_ && saved_frames_left_ >= 0) ending_->frames_left = saved_frames_left_;  // the retried frame counts once
      // (an opening started in the retried frame keeps its count: that frame does not count it, t0 == launched_at)
      if (opening_ && saved_open_frames_left_ >= 0) opening_->frames_left = saved_open_frames_left_;
    }
  }
  void scaleTimeStep(double factor) override {
    if (!(factor > 0) || !std::isfinite(factor)) return;
    substep_scale_ /= factor;
    mls_safety_scale_ *= factor;
    if (active_ && active_->region) active_->region->scaleSafety(factor);
  }
  void currentPositions(std::vector<Vec3d>& out) const override {
    out.resize(state_.positions.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3d(state_.positions[i]);
  }
  // Translation skinning: v = v0 + sum_j w_j u_j over the vertex's bound spheres, u_j the sphere's displacement;
  // during a stroke a converted sphere's displacement is eq. 13 over its points (the piece nearest the vertex).
  // While a stroke's surface opening is shown (cutting.open_surface_frames), its mesh and skin instead.
  bool currentSurface(TriangleMesh& out) const override {
    const Skin& skin = opened_ ? opened_->skin : skin_;
    out = opened_ ? opened_->mesh : rest_surface_;
    const int k = skin.k;
    for (std::size_t v = 0; v < out.vertices.size(); ++v) {
      Vec3d d;
      for (int j = 0; j < k; ++j)
        d += skinSphereDisplacement(skin.sphere[v * k + j], skin.rest_vertices[v]) * skin.weight[v * k + j];
      out.vertices[v] = skin.rest_vertices[v] + d;
    }
    return true;
  }
  MemoryReport memory() const override {
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
  void cutWallTriangles(std::vector<std::uint8_t>& out) const override { out = opened_ ? opened_->wall : wall_flags_; }
  // The viewer's layers: spheres, fixed spheres, the spheres the graspers and the mouse hold
  // (host/pbd_render_layers.h), the swept surfaces of the applied cuts and of the stroke in progress carried by the
  // spheres (host/dissection_render_layers.h), and, while a stroke is in the tissue, the nodal points where the
  // MLS solver has them now (they go back to zero when the stroke ends).
  void renderLayers(RenderLayers& out) const override {
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

  ToolSupport toolSupport() const override { return {true, true}; }
  // Grasp & drag (host/interactive_tool.h) and the mouse scalpel: each blade pose is taken back to the rest
  // configuration (restPointFromCurrent: the material point under it) and extends the stroke exactly as the
  // scripted scalpel does (spheres it reaches become nodal points, simulated in the frames that follow);
  // Release ends the stroke (re-packing). A conversion changes the sphere indices, so it releases any grasp.
  ToolResult applyTool(const ToolEvent& e) override {
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
    const BladePose world = bladeFromToolEvent(e);
    if (e.phase == ToolPhase::Press) mouse_blade_from_ = world;  // the blade's motion starts here
    mouse_blade_to_ = world;
    const BladePose rest{restPointFromCurrent(world.base, x, spheres_.rest_centers),
                         restPointFromCurrent(world.tip, x, spheres_.rest_centers)};
    const auto c0 = std::chrono::steady_clock::now();
    if (e.phase == ToolPhase::Press || !active_ || ending_ || active_->scripted >= 0) {
      completeStroke();
      beginStroke(rest, -1);
    } else {
      extendStroke(rest);
    }
    mouse_convert_ms_ += msSince(c0);
    if (e.phase == ToolPhase::Release) {
      const auto c1 = std::chrono::steady_clock::now();
      const bool swept = !active_->swept.empty();
      endStroke();
      if (swept)
        res.cut_applied = true;
      else
        res.message = "the stroke swept no surface (the blade did not move)";
      mouse_cut_ms_ += msSince(c1);
    }
    res.grasped = mouse_.held();
    return res;
  }

 private:
  struct Timers {
    double sweep_ms = 0, convert_ms = 0, exchange_ms = 0, repack_ms = 0, apply_ms = 0;
    double convert_pbd_ms = 0;  // of convert_ms: the PBD model rebuilt without the converted spheres
    double convert_prepare_ms = 0;  // the conversions' rest-configuration work (off the frame when delayed)
    double open_wait_ms = 0;        // of apply_ms: waiting for the surface opening's worker
    double convert_mls_ms = 0;  // of convert_ms: the MLS solver rebuilt on the points
    double convert_sample_ms = 0, convert_supports_ms = 0, convert_mls_model_ms = 0, convert_mls_setup_ms = 0;
    double convert_mls_build_ms = 0;
    double convert_pbd_build_ms = 0;  // of convert_pbd_ms: the host build (buildMetaballPbdModel)
    double convert_wait_ms = 0;       // of convert_ms: waiting for the MLS half after the PBD half
    double apply_region_ms = 0, apply_pbd_ms = 0;  // of convert_ms, preloaded: the two state transfers in turn
    double convert_apply_ms = 0;  // of convert_ms: a delayed conversion applied at the frame's start
    double mls_ms = 0;  // wall time of the MLS advances (launches, the GPU's work, the reductions' downloads)
    double apply_wait_ms = 0;  // of apply_ms: waiting for the stroke end's worker
  };


  // Programmatic scenes bypass the JSON loader: the same ranges, the same keys.
  static void validateCutting(const Scene& s) {
    const CuttingSpec& c = s.cutting;
    const auto range = [&](int v, int lo, int hi, const char* key) {
      if (v < lo || v > hi)
        throw InputError(s.file, std::string("cutting.") + key,
                         "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " + std::to_string(v) + ")");
    };
    range(c.samples_per_diameter, 2, 12, "samples_per_diameter");
    range(c.exchanges_per_frame, 1, 64, "exchanges_per_frame");
    range(c.pbd_substeps_per_exchange, 1, 64, "pbd_substeps_per_exchange");
    range(c.pbd_iterations, 0, 1000, "pbd_iterations");
    range(c.mls_substeps_per_exchange, 0, 100000, "mls_substeps_per_exchange");
    range(c.stroke_end_frames, 0, 120, "stroke_end_frames");
    range(c.conversion_delay_frames, 0, 1, "conversion_delay_frames");
    range(c.open_surface_frames, 0, 120, "open_surface_frames");
    if (!(c.blade_radius_m >= 0 && c.blade_radius_m <= 0.05))
      throw InputError(s.file, "cutting.blade_radius_m", "must lie in [0, 0.05] m");
    if (!(c.blade_friction >= 0 && c.blade_friction <= 2))
      throw InputError(s.file, "cutting.blade_friction", "must lie in [0, 2]");
    if (!(c.repack_boundary_offset > 0 && c.repack_boundary_offset < 1))
      throw InputError(s.file, "cutting.repack_boundary_offset", "must lie in (0, 1)");
    if (!(c.repack_spacing_factor > 0 && c.repack_spacing_factor <= 4))
      throw InputError(s.file, "cutting.repack_spacing_factor", "must lie in (0, 4]");
    if (!(c.repack_sphere_budget > 0 && c.repack_sphere_budget <= 8))
      throw InputError(s.file, "cutting.repack_sphere_budget", "must lie in (0, 8]");
  }

  // A fixed MLS substep count is checked against the nodal points' nominal stable step (the finest lattice,
  // the material's P-wave speed; section 5.1 eq. 10): a step above it is refused as bad input. At run time the
  // count is raised where the points' actual limit (densities, deformation, coupling springs) needs more.
  void checkFixedMlsSubsteps() const {
    const int fixed = scene_.cutting.mls_substeps_per_exchange;
    if (fixed <= 0) return;
    double rmin = std::numeric_limits<double>::infinity();
    for (double r : spheres_.rest_radii) rmin = std::min(rmin, r);
    const double spacing = 2.0 * rmin / scene_.cutting.samples_per_diameter;
    const MlsCoefficients<double> c = mlsCoefficients(region_.mls.material);
    const double stable = mlsStableTimeStep(c.mu, c.lambda, c.k_volume, scene_.material.density, spacing);
    const double dt = scene_.solver.frame_dt / scene_.cutting.exchanges_per_frame / fixed;
    if (dt > stable)
      throw InputError(scene_.file, "cutting.mls_substeps_per_exchange",
                       std::to_string(fixed) + " substeps give dt = " + std::to_string(dt) +
                           " s, above the nodal points' stable step " + std::to_string(stable) + " s (needs at least " +
                           std::to_string(int(std::ceil(scene_.solver.frame_dt / scene_.cutting.exchanges_per_frame / stable))) +
                           "); use more, or 0 to choose automatically");
  }

  BladePose blade(const ToolSpec& tool, double t) const {
    const ToolPose pose = toolPoseAt(tool, t);
    const Vec3d d = pose.direction * (0.5 * tool.length / std::max(norm(pose.direction), 1e-300));
    return {pose.position - d, pose.position + d};
  }

  bool coupled() const { return active_ && active_->region && active_->region->active(); }
  bool isKinematic(std::int32_t pbd) const {
    if (!active_ || !active_->region) return false;
    const std::int32_t b = active_->pbd_to_base[std::size_t(pbd)];
    return active_->region->role(b) == SphereRole::Interface;
  }

  // --- The blade as a contact (cutting.blade_radius_m > 0) ------------------------------------------------

  // The scalpel is a capsule around its blade while a stroke is in the tissue: spheres (a PBD tool capsule) and
  // nodal points (MlsSolver::setBladeContact) it covers are pushed out of it, what its sweep cuts is cut.
  bool bladeContact() const { return frame_blade_.on && scene_.cutting.blade_radius_m > 0.0; }
  static BladePose lerpBlade(const BladePose& a, const BladePose& b, double s) {
    return {a.base + (b.base - a.base) * s, a.tip + (b.tip - a.tip) * s};
  }
  void appendBladeInput(PbdFrameInput<T>& in) const {
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

  // --- Strokes --------------------------------------------------------------------------------------------

  void scriptedStrokes(double t0, double t1) {
    for (std::size_t k = 0; k < strokes_.size(); ++k) {
      ScriptedStroke& s = strokes_[k];
      if (s.done || t1 < s.start) continue;
      const auto c0 = std::chrono::steady_clock::now();
      if (!s.begun) {
        completeStroke();  // a mouse stroke still open, or a stroke end still in the making, is applied here
        s.begun = true;
        beginStroke(blade(s.tool, std::max(t0, s.start)), int(k));
      }
      extendStroke(blade(s.tool, std::min(t1, s.end)));
      if (t1 < s.end) frame_blade_ = {true, blade(s.tool, std::max(t0, s.start)), blade(s.tool, t1)};
      timers_.sweep_ms += msSince(c0) - last_convert_ms_;
      timers_.convert_ms += last_convert_ms_;
      if (t1 >= s.end) {
        s.done = true;
        const auto c1 = std::chrono::steady_clock::now();
        endStroke();
        timers_.apply_ms += msSince(c1);
      }
    }
  }

  void beginStroke(const BladePose& pose, int scripted) {
    active_ = std::make_unique<ActiveStroke>();
    active_->scripted = scripted;
    active_->base = spheres_;
    active_->swept.vertices = {pose.base, pose.tip};
    active_->base_to_pbd.resize(spheres_.size());
    active_->pbd_to_base.resize(spheres_.size());
    for (std::size_t i = 0; i < spheres_.size(); ++i) active_->base_to_pbd[i] = active_->pbd_to_base[i] = std::int32_t(i);
    // The base model's rest cell volumes: a stroke rebuild reuses those of spheres that lost no linked neighbour.
    active_->base_cell_volume.assign(model_.rest_cell_volume.begin(), model_.rest_cell_volume.end());
    active_->base_contact_inset.assign(model_.contact_inset.begin(), model_.contact_inset.end());
    last_convert_ms_ = 0;
  }

  // Extends the swept surface to `pose`; spheres the new strip enters become nodal points (with their PBD-role
  // neighbours as interface spheres), or, when none does, supports crossing the new strip are cut. Everything of
  // it but the state transfer works in the rest configuration (NodalRegion::prepareConversion, the stroke's next
  // PBD model): with cutting.conversion_delay_frames 1 that work runs on workers beside this frame and the
  // conversion is applied at the next frame's start with the state of then (applyConversion); with 0, now.
  void extendStroke(const BladePose& pose) {
    last_convert_ms_ = 0;
    ActiveStroke& a = *active_;
    const std::size_t nv = a.swept.vertices.size(), nt = a.swept.triangles.size();
    if (norm(pose.base - a.swept.vertices[nv - 2]) <= 1e-9 && norm(pose.tip - a.swept.vertices[nv - 1]) <= 1e-9) return;
    const auto c0 = std::chrono::steady_clock::now();
    applyConversion();  // one still pending (a mouse stroke's last pose): in before this strip is looked at
    extendSweptSurface(a.swept, pose);
    if (a.swept.triangles.size() == nt) {
      last_convert_ms_ = msSince(c0);
      return;
    }
    auto pc = std::make_unique<PendingConversion>();
    SweptSurface& fresh = pc->fresh;  // the new strip alone
    fresh.vertices.assign(a.swept.vertices.end() - 4, a.swept.vertices.end());
    for (std::size_t t = nt; t < a.swept.triangles.size(); ++t) {
      const auto& tri = a.swept.triangles[t];
      fresh.triangles.push_back({tri[0] - int(nv) + 2, tri[1] - int(nv) + 2, tri[2] - int(nv) + 2});
    }
    std::vector<std::int32_t> hit = findCutSpheres(fresh, a.base.rest_centers, a.base.rest_radii);
    if (a.region) hit.erase(std::remove_if(hit.begin(), hit.end(), [&](std::int32_t b) { return a.region->role(b) == SphereRole::Cut; }), hit.end());
    if (hit.empty() && !(a.region && a.region->active())) {
      last_convert_ms_ = msSince(c0);
      return;
    }
    if (!a.region) a.region = std::make_unique<NodalRegion>(a.base, regionSettings(), earlierCuts());
    NodalRegion& region = *a.region;
    const SweptSurface& swept = a.swept;  // nothing extends it before the conversion is applied
    PendingConversion* p = pc.get();
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
      p->mls = p->cut ? region.prepareConversion(std::move(from), hit, swept) : region.prepareStrip(std::move(from), p->fresh);
      if (preload) region.preload(p->mls);
      p->mls_prepare_ms = msSince(t0);
    };
    std::function<void()> pbdHalf = [] {};
    if (p->cut)
      pbdHalf = [this, p, preload, roles = region.rolesAfter(hit)] {
        const auto t0 = std::chrono::steady_clock::now();
        p->pbd = planStrokePbd(roles);
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
    last_convert_ms_ = msSince(c0);
  }

  // Brings a prepared conversion in with the state of now: the new points start rigidly attached to their spheres'
  // current state, the existing points keep theirs, the stroke's next PBD model takes the current positions and
  // velocities of the spheres it keeps (the region's load and the PBD model's run beside each other).
  void applyConversion() {
    if (!converting_) return;
    const auto c0 = std::chrono::steady_clock::now();
    convert_worker_.wait();
    prepare_pbd_worker_.wait();
    timers_.convert_wait_ms += msSince(c0);
    std::unique_ptr<PendingConversion> pc = std::move(converting_);
    NodalRegion& region = *active_->region;
    std::vector<ConvertedSphereState> st;
    st.reserve(pc->mls.sampled.size());
    for (std::int32_t b : pc->mls.sampled) st.push_back(sphereState(b));  // before the PBD model changes
    const auto installPbd = [&] {
      const auto c1 = std::chrono::steady_clock::now();
      installStrokePbd(pc->pbd);
      timers_.convert_pbd_ms += pc->pbd_prepare_ms + msSince(c1);
      timers_.convert_pbd_build_ms += pc->pbd.build_ms;
    };
    if (pc->cut && pc->pbd.preloaded) {
      // Both models are in their spare buffers: what is left is a swap and a state transfer each, shorter than
      // waking a worker for one of them (measured 0.18-0.29 ms of hand-over on the H100 host).
      const auto c1 = std::chrono::steady_clock::now();
      region.apply(pc->mls, st);
      const auto c2 = std::chrono::steady_clock::now();
      installPbd();
      timers_.apply_region_ms += std::chrono::duration<double, std::milli>(c2 - c1).count();
      timers_.apply_pbd_ms += msSince(c2);
    } else if (pc->cut) {
      timers_.convert_wait_ms += convert_worker_.runBeside([&region, &pc, &st] { region.apply(pc->mls, st); }, installPbd);
    } else {
      region.apply(pc->mls, st);
    }
    timers_.convert_prepare_ms += std::max(pc->mls_prepare_ms, pc->pbd_prepare_ms);
    if (!pc->mls.rebuild) return;
    timers_.convert_mls_ms += region.lastRebuildMs();
    const NodalRegion::ConversionTimes& ct = region.lastConversionTimes();
    timers_.convert_sample_ms += ct.sample_ms;
    timers_.convert_supports_ms += ct.supports_ms;
    timers_.convert_mls_model_ms += ct.model_ms;
    timers_.convert_mls_setup_ms += ct.setup_ms;
    timers_.convert_mls_build_ms += ct.model_build_ms;
  }

  NodalRegionSettings regionSettings() const {
    NodalRegionSettings s = region_;
    s.mls.safety = std::min(1.0, s.mls.safety * mls_safety_scale_);  // the guard's retries (scaleTimeStep)
    return s;
  }
  std::vector<const SweptSurface*> earlierCuts() const {
    std::vector<const SweptSurface*> out;
    for (const SweptSurface& c : earlier_cuts_) out.push_back(&c);
    return out;
  }

  // A base sphere's current state from the PBD model (it is still there when it is converted).
  ConvertedSphereState sphereState(std::int32_t b) const {
    ConvertedSphereState s;
    const std::int32_t i = active_->base_to_pbd[std::size_t(b)];
    s.position = Vec3d(state_.positions[std::size_t(i)]);
    s.velocity = Vec3d(state_.velocities[std::size_t(i)]);
    if (std::size_t(i) < state_.rotations.size()) s.rotation = Mat3d(pbd::quatToMatrix(state_.rotations[std::size_t(i)]));
    return s;
  }

  // The PBD model during a stroke: the base spheres that are not cut (interface spheres stay, kinematic), in base
  // order, with the links among them (a link never crosses the stroke without entering one of its spheres);
  // base_to_kept maps base indices to theirs (-1: cut).
  static MetaballModel uncutSpheres(const MetaballModel& base, const std::vector<SphereRole>* roles,
                                    std::vector<std::int32_t>& base_to_kept) {
    MetaballModel m;
    base_to_kept.assign(base.size(), -1);
    for (std::size_t b = 0; b < base.size(); ++b) {
      if (roles && (*roles)[b] == SphereRole::Cut) continue;
      base_to_kept[b] = std::int32_t(m.size());
      m.rest_centers.push_back(base.rest_centers[b]);
      m.rest_radii.push_back(base.rest_radii[b]);
      m.masses.push_back(base.masses[b]);
    }
    for (std::size_t l = 0; l < base.links.size(); ++l) {
      const std::int32_t i = base_to_kept[std::size_t(base.links[l][0])], j = base_to_kept[std::size_t(base.links[l][1])];
      if (i < 0 || j < 0) continue;
      m.links.push_back({std::min(i, j), std::max(i, j)});
      m.link_rest_lengths.push_back(base.link_rest_lengths[l]);
    }
    return m;
  }

  // The stroke's next PBD model for the given roles, built (rest configuration only: a worker may run it while the
  // frame goes on with the current model).
  struct StrokePbdPlan {
    MetaballModel spheres;
    std::vector<std::int32_t> base_to_pbd, pbd_to_base;
    PbdModel<T> built;
    double build_ms = 0;
    bool preloaded = false;  // `built` is in spare_backend_ already (preloadStrokePbd)
  };
  // While a stroke may be preloading, PBD frames that one grid launch runs (docs/pbd.md, "Grid frame") are launched
  // directly: no capture then waits for a worker's load (each stroke model is new anyway). Larger models keep their
  // graphs (their direct path is ~170 launches); a capture then waits for a load in progress (deviceCaptureMutex).
  bool directFrameFits(const PbdStepParams<T>& p) const {
    return p.solver == PbdSolverKind::Jacobi && model_.size() <= std::size_t(std::max(0, p.grid_max_particles));
  }
  // On the worker that planned it: the plan's model into the spare backend (the one before last), while the frame
  // goes on with backend_. Only the worker touches spare_backend_ until the plan is installed.
  void preloadStrokePbd(StrokePbdPlan& plan) {
    const std::lock_guard<std::mutex> lock(deviceCaptureMutex());
    if (!spare_backend_) spare_backend_ = makePbdBackend<T>(backend_->kind());
    spare_backend_->setModel(plan.built);
    plan.preloaded = true;
  }
  StrokePbdPlan planStrokePbd(const std::vector<SphereRole>& roles) const {
    const ActiveStroke& a = *active_;
    StrokePbdPlan p;
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
    // A kept sphere's inset depends on its own rest ball alone: the base model's value, not a new surface query.
    MetaballPbdOptions opt = pbdOptions(std::move(known), false);
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

  // Makes the plan the stroke's PBD model, its spheres at their current positions and velocities.
  void installStrokePbd(StrokePbdPlan& p) {
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

  // The blade leaves. Every heavy part of a stroke's end works in the rest configuration (Algorithm 1 on the
  // points' rest positions, the new PBD model's build, the surface split, the skin binding: host/cut_stroke_end.h),
  // so it starts now on a worker and is applied cutting.stroke_end_frames frames later, the nodal points and
  // spheres simulated meanwhile as during the stroke; the state transfer (applyStrokeEnd) reads the state then.
  // A fixed frame count, not "when the worker is done", keeps runs deterministic. 0 frames: applied now.
  void endStroke() {
    applyConversion();  // the stroke's last strip
    ActiveStroke& a = *active_;
    if (a.swept.empty()) {
      ++cuts_done_;
      active_.reset();
      return;
    }
    auto e = std::make_shared<PendingStrokeEnd>();
    StrokeEndInput& in = e->input;
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
    e->frames_left = scene_.cutting.stroke_end_frames;
    ending_ = e;
    if (e->frames_left <= 0) {  // due now: computed on this thread (applyStrokeEnd), no worker
      applyStrokeEnd();
      return;
    }
    if (!end_worker_.done()) return;  // still on an end given up on (starved): this one is computed when due
    e->on_worker = true;
    // The task holds the pending end (shared): applyStrokeEnd may give up on it and go on without it.
    end_worker_.start([e, split = &end_split_worker_, opt = pbdOptions({}, false), gate = idleWorkerGate()] {
      if (gate) gate();
      e->result = computeStrokeEnd(e->input, *split,
                                   [&e, &opt](const MetaballModel& m) { e->pbd = buildMetaballPbdModel<T>(m, opt); });
    });
  }

  // How long a frame waits for an idle-priority worker's due result before computing it itself (ms): as long as
  // computing it took the last time (at least 10 ms; 50 before any). Then the worst case is about twice the work
  // instead of however long a busy machine starves the worker (its OpenMP threads stay idle even when boosted);
  // the result is the same either way, so runs stay deterministic.
  static double patience(double last_ms) { return last_ms > 0 ? std::min(std::max(last_ms, 10.0), 500.0) : 50.0; }

  // Ends whatever stroke there is and applies its end now (a new stroke begins).
  void completeStroke() {
    if (!active_) return;
    if (!ending_) endStroke();
    if (ending_) applyStrokeEnd();
  }

  // The stroke end computed by the worker, applied with the state of now: interface spheres return to PBD at their
  // eq. 13 position, every new sphere takes the mass-weighted mean displacement and velocity of the points it took,
  // the other spheres keep theirs; the split surface and the new skin replace the old. The nodal points go back to
  // zero.
  void applyStrokeEnd() {
    const auto c0 = std::chrono::steady_clock::now();
    discardOpening();
    std::shared_ptr<PendingStrokeEnd> e = std::move(ending_);
    bool here = !e->on_worker;
    if (e->on_worker && !end_worker_.done()) {  // the frames ran out before the workers: normal priority now
      end_worker_.boost();
      end_split_worker_.boost();
      here = !end_worker_.waitFor(patience(last_end_.worker_ms));
    }
    if (e->on_worker && !here) end_worker_.wait();  // rethrows what the worker threw
    // Computed here: the worker's copy of the result is left to it (it finishes in the background).
    StrokeEndResult own;
    PbdModel<T> own_pbd;
    if (here) {
      const MetaballPbdOptions opt = pbdOptions({}, false);
      own = computeStrokeEnd(e->input, convert_worker_,
                             [&](const MetaballModel& m) { own_pbd = buildMetaballPbdModel<T>(m, opt); });
    }
    last_end_here_ = here && e->on_worker;
    timers_.apply_wait_ms += msSince(c0);
    std::unique_ptr<ActiveStroke> a = std::move(active_);
    StrokeEndResult& r = here ? own : e->result;
    PbdModel<T>& built = here ? own_pbd : e->pbd;
    ++cuts_done_;
    last_points_ = 0;
    last_added_ = 0;
    if (r.repacked) {
      last_points_ = a->region->pointCount();
      const NodalRegionFinal fin = a->region->finish(false);
      std::map<std::int32_t, std::size_t> iface;
      for (std::size_t k = 0; k < fin.interface_ids.size(); ++k) iface[fin.interface_ids[k]] = k;
      std::vector<Vec3d> x, v;
      std::vector<std::int32_t> old_to_new(model_.size(), -1);
      for (std::size_t b = 0; b < a->base.size(); ++b) {
        if (a->region->role(std::int32_t(b)) == SphereRole::Cut) continue;
        const std::int32_t pbd = a->base_to_pbd[b];
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
      for (std::size_t i = 0; i < e->input.points.size(); ++i) {
        if (e->input.points.context[i]) continue;
        const std::size_t s = std::size_t(rp.owner[i]);
        nu[s] += fin.displacement[i] * e->input.points.mass[i];
        nv[s] += fin.velocity[i] * e->input.points.mass[i];
        nm[s] += e->input.points.mass[i];
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
    if (r.split) {
      surface_ = std::make_shared<const CutSurfaceState>(std::move(r.surface));
      surface_components_ = r.surface_components;  // from the split's own output check: no second analysis
      rest_surface_ = surface_->mesh;
      wall_flags_ = surface_->wall;
      surface_split_ = true;
    }
    earlier_cuts_.push_back(std::move(a->swept));
    skin_ = Skin{r.skin.k, std::move(r.skin.rest_vertices), std::move(r.skin.sphere), std::move(r.skin.weight)};
    skin_rest_centres_ = spheres_.rest_centers;
    sphere_components_ = r.sphere_components;
    last_split_failure_ = r.split_failure;
    last_end_ = {r.total_ms, r.repack_ms, r.build_ms, r.split_ms, r.bind_ms};
  }

  // --- The surface opened during a stroke (cutting.open_surface_frames > 0) -------------------------------

  // At a frame's start, when no opening is in the making and the sweep grew since the last one: a worker splits
  // the surface as it was before the stroke along the sweep so far (a slit ending where the blade is) and binds the
  // skin of the split surface to the stroke's base spheres across every cut including the partial sweep, so each
  // side of the slit follows its own spheres and, through cut spheres, the piece of their points on its side
  // (skinSphereDisplacement). It is shown from the start of the frame open_surface_frames frames later until the
  // next one or the stroke's end, which splits the surface before the stroke along the whole sweep as without it:
  // display only, no simulated result changes. A split the sweep so far does not allow leaves the last one shown.
  void openSurface(double t0) {
    const int n = scene_.cutting.open_surface_frames;
    if (n <= 0 || opening_ || !active_ || ending_) return;
    ActiveStroke& a = *active_;
    if (a.swept.triangles.empty() || a.swept.triangles.size() == a.opened_triangles) return;
    a.opened_triangles = a.swept.triangles.size();
    auto job = std::make_shared<PendingOpening>();
    job->launched_at = t0;
    job->frames_left = n;
    job->cuts = earlier_cuts_;
    job->cuts.push_back(a.swept);
    job->spheres = a.base;
    job->surface = surface_;
    job->file = scene_.file;
    opening_ = job;
    if (!open_worker_.done()) return;  // still on an opening given up on (starved): this one is computed when due
    job->on_worker = true;
    open_worker_.start([job, gate = idleWorkerGate()] {  // the task holds its job: it may be given up on
      if (gate) gate();
      computeOpening(*job);
    });
  }

  // An opening's split and binding (pure: the same job gives the same result on any thread).
  template <typename Job>  // PendingOpening (declared with the members below)
  static void computeOpening(Job& job) {
    const auto c0 = std::chrono::steady_clock::now();
    try {
      job.state = *job.surface;
      job.split = applySurfaceCut(job.state, job.cuts.back()).split;
      if (job.split) {
        const int k = std::min<int>(4, int(job.spheres.size()));
        job.skin = bindSkinAcrossCuts(job.state, job.spheres, job.cuts, k, job.file);
      }
    } catch (const std::exception&) {
      // A sweep the split refuses (or any failure of it): nothing new to show. Display only, so it never ends the
      // run; the stroke's end splits for good and reports.
      job.split = false;
    }
    job.worker_ms = msSince(c0);
  }

  // Shows the opening due now: the worker's, or, when the worker is not done within patience(), one computed here
  // from a copy of its inputs (the same result; the worker's copy is left to it).
  void applyOpening() {
    const auto c0 = std::chrono::steady_clock::now();
    std::shared_ptr<PendingOpening> job = std::move(opening_);
    bool here = !job->on_worker;
    if (job->on_worker && !open_worker_.done()) {
      open_worker_.boost();
      here = !open_worker_.waitFor(patience(last_open_ms_));
    }
    if (here) {  // computed here from a copy of its inputs: a worker given up on still reads the job's
      auto own = std::make_shared<PendingOpening>();
      own->cuts = job->cuts;
      own->spheres = job->spheres;
      own->surface = job->surface;
      own->file = job->file;
      computeOpening(*own);
      job = own;
      ++opened_here_;
    }
    timers_.open_wait_ms += msSince(c0);
    last_open_ms_ = job->worker_ms;
    if (!job->split) return;
    auto o = std::make_unique<OpenedSurface>();
    o->mesh = job->state.mesh;
    o->wall = job->state.wall;
    o->skin = Skin{job->skin.k, std::move(job->skin.rest_vertices), std::move(job->skin.sphere), std::move(job->skin.weight)};
    opened_ = std::move(o);
  }

  // The stroke's end replaces whatever opening there is (one in the making finishes on its worker, unused).
  void discardOpening() {
    opening_.reset();
    opened_.reset();
  }

  // --- PBD model ------------------------------------------------------------------------------------------

  // The PBD model's build options for this scene (pure: a worker may build with them).
  MetaballPbdOptions pbdOptions(std::vector<double> known_cell_volumes, bool require_fixed_held) const {
    MetaballPbdOptions opt;
    opt.youngs_modulus = scene_.material.youngs_modulus;
    opt.stretch_compliance = scene_.pbd.stretch_compliance;
    opt.laplacian_compliance = scene_.pbd.laplacian_compliance;
    opt.fixed = scene_.fixed;
    opt.colliders = scene_.colliders;
    if (!scene_.colliders.empty())
      opt.surface_depth = [t = tissue_](const Vec3d& x) { return -t->signedDistance(x).distance; };
    opt.file = scene_.file;
    opt.require_fixed_held = require_fixed_held;
    opt.volume_samples = scene_.pbd.volume_preservation ? 64 : 0;
    opt.coloring = params_.solver == PbdSolverKind::GaussSeidel;  // Jacobi never reads it (a rebuild per conversion)
    opt.known_cell_volumes = std::move(known_cell_volumes);
    return opt;
  }

  // Makes `built` (the PBD model of `m`) the backend's model with the given positions and velocities; old_to_new
  // maps the previous PBD indices (grasps follow their spheres).
  void installSpheres(MetaballModel m, PbdModel<T> built, const std::vector<Vec3d>& x, const std::vector<Vec3d>& v,
                      const std::vector<std::int32_t>& old_to_new, bool preloaded = false) {
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

  // Binds the surface to the spheres. After a cut each vertex binds only to spheres it sees without crossing
  // any cut (no skin weight across a swept surface; host/cut_surface_state.h).
  void bindSurface() {
    skin_rest_centres_ = spheres_.rest_centers;
    const int k = std::min<int>(4, int(spheres_.size()));
    const SkinBinding b = earlier_cuts_.empty() ? bindSkin(rest_surface_, spheres_, k, scene_.file)
                                                : bindSkinAcrossCuts(*surface_, spheres_, earlier_cuts_, k, scene_.file);
    skin_ = Skin{b.k, b.rest_vertices, b.sphere, b.weight};
  }

  // The displacement of skin sphere s (an index of the model the skin was bound to: during a stroke, the
  // stroke's base) seen from rest vertex p.
  Vec3d skinSphereDisplacement(std::int32_t s, const Vec3d& p) const {
    std::int32_t i = s;
    if (active_) {
      Vec3d u;
      if (active_->region && active_->region->role(s) == SphereRole::Cut && active_->region->sphereDisplacement(s, p, u))
        return u;
      i = active_->base_to_pbd[std::size_t(s)];
      if (i < 0) return Vec3d();
    }
    return Vec3d(state_.positions[std::size_t(i)]) - skin_rest_centres_[std::size_t(s)];
  }

  // --- Graspers -------------------------------------------------------------------------------------------

  void updateGraspers(double t0) {
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

  // --- The coupled frame (section 5.3) --------------------------------------------------------------------

  // K = cutting.exchanges_per_frame intervals of frame_dt / K. Each: the springs' anchors from the PBD spheres
  // (held over the interval), the nodal points advance (MLS, eqs. 4-10, with the springs' share eqs. 11-12 on
  // the interface spheres' points every substep), then the interface spheres take their eq. 13 positions as
  // kinematic targets of the PBD step over the same interval (pbd_substeps_per_exchange substeps of
  // cutting.pbd_iterations iterations). Tools and grasps are interpolated over the frame.
  void coupledFrame(double frame_dt, const PbdFrameInput<T>& in, PbdFrameStats& st, MlsFrameStats& mls, bool& mls_finite,
                    int& exchanges, int& pbd_substeps) {
    ActiveStroke& a = *active_;
    NodalRegion& region = *a.region;
    const int K = scene_.cutting.exchanges_per_frame;
    const double dt = frame_dt / K;
    PbdStepParams<T> p = params_;
    p.frame_dt = T(dt);
    p.substeps = std::max(1, int(std::ceil(scene_.cutting.pbd_substeps_per_exchange * substep_scale_ - 1e-9)));
    if (scene_.cutting.pbd_iterations > 0) p.iterations = scene_.cutting.pbd_iterations;
    if (preload_ && directFrameFits(p)) p.use_graph = false;  // no capture beside the workers' loads
    std::vector<std::int32_t> ids;
    std::vector<Vec3d> targets;
    region.interfacePositions(ids, targets);
    std::vector<Vec3<T>> from(ids.size());
    for (std::size_t k = 0; k < ids.size(); ++k) from[k] = state_.positions[std::size_t(a.base_to_pbd[std::size_t(ids[k])])];
    std::vector<char> kinematic(model_.size(), 0);
    for (std::int32_t b : ids) kinematic[std::size_t(a.base_to_pbd[std::size_t(b)])] = 1;
    const auto pbdPosition = [&](std::int32_t b) { return Vec3d(state_.positions[std::size_t(a.base_to_pbd[std::size_t(b)])]); };
    st = PbdFrameStats{};
    for (int e = 0; e < K; ++e) {
      if (bladeContact()) {
        const double b0 = double(e) / K, b1 = double(e + 1) / K;
        region.setBlade(lerpBlade(frame_blade_.from, frame_blade_.to, b0), lerpBlade(frame_blade_.from, frame_blade_.to, b1),
                        scene_.cutting.blade_radius_m, scene_.cutting.blade_friction);
      } else {
        region.setBlade({}, {}, 0.0);
      }
      const auto cm = std::chrono::steady_clock::now();
      const MlsFrameStats ms = region.advance(dt, scene_.cutting.mls_substeps_per_exchange, pbdPosition);
      timers_.mls_ms += msSince(cm);
      mls.substeps += ms.substeps;
      mls.ms_integrate += ms.ms_integrate;
      mls.ms_coupling += ms.ms_coupling;
      mls.ms_stress += ms.ms_stress;
      mls.ms_forces += ms.ms_forces;
      mls.ms_reduce += ms.ms_reduce;
      mls.ms_substeps += ms.ms_substeps;
      mls.totals = ms.totals;
      if (!ms.totals.finite) {
        mls_finite = false;
        if (e > 0) backend_->getState(state_);  // the exchanges before read the positions alone
        break;
      }
      const auto c0 = std::chrono::steady_clock::now();
      region.interfacePositions(ids, targets);  // eq. 13
      PbdFrameInput<T> ie;
      const T s0 = T(double(e) / K), s1 = T(double(e + 1) / K);
      for (std::size_t k = 0; k < ids.size(); ++k) {
        ie.kinematic_ids.push_back(a.base_to_pbd[std::size_t(ids[k])]);
        ie.kinematic_from.push_back(from[k]);
        ie.kinematic_to.push_back(Vec3<T>(targets[k]));
        from[k] = Vec3<T>(targets[k]);
      }
      for (std::size_t k = 0; k < in.attach_ids.size(); ++k) {
        if (kinematic[std::size_t(in.attach_ids[k])]) continue;  // held by its points now
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
      ++exchanges;
      pbd_substeps += p.substeps;
      if (!ps.finite) {
        st.finite = false;
        st.failure_particle = ps.failure_particle;
        break;
      }
    }
  }

  // --- Frame report ---------------------------------------------------------------------------------------

  void report(FrameReport& rep, const MlsFrameStats& mls, int exchanges) const {
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
    std::size_t pending = 0, interface = 0;
    if (active_ && active_->region)
      for (std::size_t b = 0; b < active_->base.size(); ++b) {
        pending += active_->region->role(std::int32_t(b)) == SphereRole::Cut;
        interface += active_->region->role(std::int32_t(b)) == SphereRole::Interface;
      }
    const MlsModelStats* ms = region && region->solver() ? &region->solver()->modelStats() : nullptr;
    rep.counters["spheres"] = double(model_.size());
    rep.counters["mass_kg"] = mass;
    rep.counters["cut_spheres_pending"] = double(pending);
    rep.counters["interface_spheres"] = double(interface);
    rep.counters["nodal_points"] = region ? double(region->pointCount()) : 0.0;
    rep.counters["nodal_max_displacement_m"] = region ? region->lastReduction().max_displacement : 0.0;
    rep.counters["coupling_springs"] = region ? double(region->springCount()) : 0.0;
    rep.counters["coupling_spring_energy_j"] = spring;
    rep.counters["coupling_exchanges"] = double(exchanges);
    rep.counters["mls_substeps"] = double(mls.substeps);
    rep.counters["mls_isolated_points"] = ms ? double(ms->isolated) : 0.0;
    rep.counters["mls_regularised_points"] = ms ? double(ms->regularised) : 0.0;
    rep.counters["supports_cut"] = region ? double(region->supportsRemoved()) : 0.0;
    rep.counters["cuts_applied"] = double(cuts_done_);
    rep.counters["sphere_components"] = double(sphere_components_);
    rep.counters["links"] = double(spheres_.links.size());
    int grasped = mouse_.held();
    for (const Grasper& g : graspers_) grasped += int(g.grasped().size());
    rep.counters["grasped"] = double(grasped);
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
    rep.counters["sweep_ms"] = timers_.sweep_ms;
    rep.counters["convert_ms"] = timers_.convert_ms;
    rep.counters["repack_ms"] = timers_.repack_ms;
    rep.counters["cut_apply_ms"] = timers_.apply_ms;
    rep.counters["stroke_end_pending"] = ending_ ? 1.0 : 0.0;
    rep.counters["surface_opened"] = opened_ ? 1.0 : 0.0;  // a stroke's partial opening is shown
    rep.counters["surface_open_pending"] = opening_ ? 1.0 : 0.0;
    rep.counters["surface_open_ms"] = last_open_ms_;  // the last applied opening's worker time
    rep.counters["surface_open_here"] = double(opened_here_);  // openings computed on the frame's thread so far
    rep.counters["surface_split_failed"] = last_split_failure_.empty() ? 0.0 : 1.0;  // the last applied cut's
    rep.counters["stroke_end_worker_ms"] = last_end_.worker_ms;
    rep.counters["stroke_end_here"] = last_end_here_ ? 1.0 : 0.0;  // the last end: its worker given up on
    rep.counters["stroke_end_repack_ms"] = last_end_.repack_ms;
    rep.counters["stroke_end_build_ms"] = last_end_.build_ms;
    rep.counters["stroke_end_split_ms"] = last_end_.split_ms;
    rep.counters["stroke_end_bind_ms"] = last_end_.bind_ms;
  }

  Scene scene_;
  std::vector<ScriptedStroke> strokes_;
  std::vector<Grasper> graspers_, saved_graspers_;
  std::vector<ToolSpec> probes_;
  NodalRegionSettings region_;
  double reference_mass_ = 0.0, reference_radius_ = 0.0;  // kg, m: the organ's mean sphere before any cut
  std::shared_ptr<const pack::SurfaceDistance> tissue_;   // the organ's rest surface (inside test)
  MetaballModel spheres_;  // the spheres of the PBD model (during a stroke: the base minus the cut ones)
  TriangleMesh rest_surface_;  // the surface after every cut so far (rest configuration) = surface_.mesh
  TriangleMesh collider_mesh_;  // the scene's colliders drawn around the organ (RenderLayers::colliders)
  // The split surface with its wall flags and binding probes; replaced, never changed in place (workers read it).
  std::shared_ptr<const CutSurfaceState> surface_;
  struct Skin {  // translation skinning slots v * k + j (sphere index into the bound model, weight)
    int k = 0;
    std::vector<Vec3d> rest_vertices;
    std::vector<std::int32_t> sphere;
    std::vector<double> weight;
  } skin_;
  std::vector<Vec3d> skin_rest_centres_;  // rest centres of the model the skin is bound to
  PbdModel<T> model_;
  std::unique_ptr<PbdBackend<T>> backend_;
  PbdStepParams<T> params_;
  PbdState<T> state_, saved_state_;
  std::unique_ptr<ActiveStroke> active_;
  // A stroke's end in the making (active_ is that stroke, its points still simulated): the worker's inputs and
  // result, and the frames left until it is applied.
  struct PendingStrokeEnd {
    StrokeEndInput input;
    StrokeEndResult result;
    PbdModel<T> pbd;  // the new PBD model, built on the worker
    int frames_left = 0;
    bool on_worker = false;  // started on the end workers (else computed when applied)
  };
  std::shared_ptr<PendingStrokeEnd> ending_;
  bool last_end_here_ = false;  // the last applied end was computed on the frame's thread, the worker given up on
  // A conversion in the making (cutting.conversion_delay_frames 1), or being applied: the strip, the region's
  // update and the stroke's next PBD model, prepared on the workers below.
  struct PendingConversion {
    double launched_at = 0;  // s: the start of the frame the blade entered in (applied at a later frame's start)
    SweptSurface fresh;      // the new strip alone
    bool cut = false;        // spheres were cut: `pbd` is the stroke's next PBD model
    NodalUpdate mls;
    StrokePbdPlan pbd;
    double mls_prepare_ms = 0, pbd_prepare_ms = 0;
  };
  std::unique_ptr<PendingConversion> converting_;
  // A surface opening in the making (its worker's inputs and result) and the one shown (openSurface).
  struct PendingOpening {
    double launched_at = 0;  // s: the start of the frame it was started in
    int frames_left = 0;
    bool on_worker = false;  // started on open_worker_ (else computed when due)
    std::vector<SweptSurface> cuts;  // the earlier cuts, then the stroke's sweep so far
    MetaballModel spheres;           // the stroke's base
    std::shared_ptr<const CutSurfaceState> surface;  // the surface before the stroke
    std::string file;
    CutSurfaceState state;           // a copy of it, then split
    bool split = false;
    SkinBinding skin;
    double worker_ms = 0;
  };
  struct OpenedSurface {
    TriangleMesh mesh;
    std::vector<std::uint8_t> wall;
    Skin skin;
  };
  std::shared_ptr<PendingOpening> opening_;
  std::unique_ptr<OpenedSurface> opened_;
  int saved_open_frames_left_ = -1;
  long opened_here_ = 0;
  double last_open_ms_ = 0;
  int saved_frames_left_ = -1;
  std::string last_split_failure_;  // why the last applied cut left the surface unsplit (empty: it did not)
  struct EndTimes {
    double worker_ms = 0, repack_ms = 0, build_ms = 0, split_ms = 0, bind_ms = 0;
  } last_end_;  // the worker's times of the last applied stroke end
  std::vector<SweptSurface> earlier_cuts_;  // every stroke finished so far (rest configuration)
  std::size_t last_points_ = 0, last_added_ = 0;
  RepackResult last_repack_;
  bool surface_split_ = false;
  int cuts_done_ = 0;
  long version_ = 0, saved_version_ = -1;  // topology version (every PBD rebuild)
  int surface_components_ = 1, sphere_components_ = 1;
  std::vector<std::uint8_t> wall_flags_;  // per rest_surface_ triangle: 1 = cut wall
  PbdMouseGrasp mouse_;                   // the viewer's grasp
  mutable CutLayerBinding cut_layers_;    // renderLayers' binding of the swept surfaces (rebuilt when they change)
  Timers timers_;
  double last_convert_ms_ = 0.0, mouse_cut_ms_ = 0.0, mouse_convert_ms_ = 0.0;
  struct FrameBlade {  // the blade over this frame while a stroke is in the tissue (world, m)
    bool on = false;
    BladePose from, to;
  } frame_blade_;
  BladePose mouse_blade_from_, mouse_blade_to_;  // the mouse blade at the last frame's end and now (world)
  int base_substeps_ = 4;
  double substep_scale_ = 1.0, mls_safety_scale_ = 1.0;
  double time_ = 0, saved_time_ = 0;
  // CUDA with delayed conversions: the workers load each conversion's models into spare device buffers (the PBD
  // backend and the MLS solver before last) beside the frame; INCISION_NO_PRELOAD=1 loads them in the applying frame
  // instead (for A/B runs). Declared before the workers: a worker still loading it is joined before it goes.
  bool preload_ = false;
  std::unique_ptr<PbdBackend<T>> spare_backend_;
  // A stroke's end and its surface split, at idle priority until the end is due (on two cores they would otherwise
  // slow the frames simulated meanwhile 2.5-fold); declared last, joined first.
  BackgroundTask end_split_worker_{true}, end_worker_{true};
  // A conversion's region half beside its PBD half (at normal priority: it is due at the next frame).
  BackgroundTask convert_worker_, prepare_pbd_worker_;
  BackgroundTask open_worker_{true};  // surface openings, idle priority as a stroke's end
};

}  // namespace

std::unique_ptr<SimulationModel> makeDissectionSimulation(const Scene& scene, BackendKind backend, Precision precision) {
  if (precision == Precision::Float64) return std::make_unique<DissectionSimulation<double>>(scene, backend);
  return std::make_unique<DissectionSimulation<float>>(scene, backend);
}

}  // namespace inc
