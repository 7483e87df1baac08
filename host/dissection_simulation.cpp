// DissectionSimulation: PBD metaballs + scripted scalpel; the cut pipeline of section 5 applied when the blade stops.
#include "host/dissection_simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "host/cut_surface_state.h"
#include "host/cut_nodal_points.h"
#include "host/cut_swept_surface.h"
#include "host/dissection_render_layers.h"
#include "host/grasper.h"
#include "host/input_error.h"
#include "host/interactive_tool.h"
#include "host/metaball_simulation.h"
#include "host/organ_shapes.h"
#include "host/pbd_builders.h"
#include "host/pbd_model.h"
#include "host/pbd_render_layers.h"
#include "host/skin_binding.h"

namespace inc {

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

template <typename T>
class DissectionSimulation final : public SimulationModel {
 public:
  DissectionSimulation(const Scene& scene, BackendKind backend) : scene_(scene), kind_(backend) {
    const std::string& f = scene.file;
    if (!scene.models.cutting) throw InputError(f, "models.cutting", "the dissection model needs cutting: true");
    if (!scene.models.pbd_metaballs) throw InputError(f, "models.pbd_metaballs", "cutting needs the PBD metaball organ");
    if (scene.pbd.iterations < 1) throw InputError(f, "pbd.iterations", "must be >= 1");
    for (const ToolSpec& t : scene.tools)
      if (t.kind == "scalpel") {
        scalpel_ = t;
        has_scalpel_ = true;
        break;
      }
    // With models.haptics the blade may come only from a haptic device (applyTool), without a scripted one.
    if (!has_scalpel_ && !scene.models.haptics) throw InputError(f, "tools", "cutting needs a tool of kind \"scalpel\"");
    if (has_scalpel_ && scalpel_.path.size() < 2)
      throw InputError(f, "tools." + scalpel_.name + ".path", "a scalpel needs >= 2 keyframes");
    if (has_scalpel_ && !(scalpel_.length > 0)) throw InputError(f, "tools." + scalpel_.name + ".length_m", "must be > 0");
    params_.solver = parsePbdSolver(scene.pbd.solver, f, "pbd.solver");
    params_.iterations = scene.pbd.iterations;
    // CUDA single-block fused frame: measured on an H100 (docs/BENCHMARKS.md) it beats per-phase launches for
    // Gauss-Seidel up to thousands of spheres, but for Jacobi only below ~300 spheres.
    params_.fused_max_particles = params_.solver == PbdSolverKind::Jacobi ? 256 : 4096;
    params_.xpbd = scene.pbd.xpbd;
    params_.gravity = Vec3<T>(scene.solver.gravity);
    params_.damping = T(scene.material.damping);
    params_.volume_preservation = scene.pbd.volume_preservation;
    params_.volume_influence = T(2.0 * scene.geometry.spacing);
    base_substeps_ = scene.solver.substeps > 0 ? scene.solver.substeps : 4;
    spheres_ = buildSceneMetaballs(scene);
    rest_surface_ = sceneSurfaceMesh(scene);
    backend_ = makePbdBackend<T>(backend);
    rebuild(nullptr);
    sphere_components_ = sphereGraphComponents(spheres_);
    saveCheckpoint();
  }

  std::string name() const override { return "dissection"; }
  BackendKind backend() const override { return backend_->kind(); }
  std::size_t particleCount() const override { return model_.size(); }

  FrameReport advance(double frame_dt) override {
    FrameReport rep;
    const double t0 = time_, t1 = time_ + frame_dt;
    double sweep_ms = 0.0, apply_ms = 0.0;
    if (has_scalpel_ && !cut_applied_ && t1 >= scalpel_.path.front().t) {
      const double ts = scalpel_.path.front().t, te = scalpel_.path.back().t;
      const auto c0 = std::chrono::steady_clock::now();
      // One strip per frame from the blade at max(t0, ts) to the blade at min(t1, te) (eq.-free: section 5.1).
      const BladePose b1 = blade(std::min(t1, te));
      if (swept_.vertices.empty()) {
        const BladePose b0 = blade(std::max(t0, ts));
        swept_.vertices = {b0.base, b0.tip};
      }
      const Vec3d last = swept_.vertices[swept_.vertices.size() - 2];
      if (norm(b1.base - last) > 1e-12) extendSweptSurface(swept_, b1);
      pending_ = swept_.empty() ? 0 : findCutSpheres(swept_, spheres_.rest_centers, spheres_.rest_radii).size();
      sweep_ms = msSince(c0);
      if (t1 >= te) {
        const auto c1 = std::chrono::steady_clock::now();
        cut_applied_ = true;
        applyCut(swept_);
        apply_ms = msSince(c1);
      }
    }
    apply_ms += mouse_cut_ms_;
    mouse_cut_ms_ = 0.0;
    PbdFrameInput<T> in;
    appendMouseAttachments(mouse_, in);
    PbdStepParams<T> p = params_;
    p.frame_dt = T(frame_dt);
    p.substeps = std::max(1, int(std::ceil(base_substeps_ * substep_scale_ - 1e-9)));
    const PbdFrameStats st = backend_->advanceFrame(p, in);
    backend_->getState(state_);
    mouse_.frameDone();
    time_ = t1;
    rep.substeps = p.substeps;
    rep.dt = frame_dt / p.substeps;
    rep.stages = st.stages;
    rep.stages.push_back({"cut_sweep", sweep_ms});
    rep.stages.push_back({"cut_apply", apply_ms});
    rep.finite = st.finite;
    if (!st.finite) {
      rep.failure_stage = "pbd";
      rep.failure_particle = st.failure_particle;
    }
    double ke = 0, pe = 0, disp = 0;
    for (std::size_t i = 0; i < model_.size(); ++i) {
      const Vec3d x(state_.positions[i]), x0(model_.rest_positions[i]), v(state_.velocities[i]);
      ke += 0.5 * double(model_.masses[i]) * norm2(v);
      pe -= double(model_.masses[i]) * dot(scene_.solver.gravity, x - x0);
      disp = std::max(disp, norm(x - x0));
    }
    rep.kinetic_energy = ke;
    rep.potential_energy = pe;
    rep.max_displacement = disp;
    rep.counters["spheres"] = double(model_.size());
    rep.counters["links"] = double(spheres_.links.size());
    rep.counters["cut_spheres_pending"] = double(pending_);
    rep.counters["cuts_applied"] = double(cuts_done_);
    rep.counters["sphere_components"] = double(sphere_components_);
    rep.counters["grasped"] = double(mouse_.held());
    rep.counters["nodal_points_last_cut"] = double(last_points_);
    rep.counters["spheres_added_last_cut"] = double(last_added_);
    rep.counters["surface_split"] = surface_split_ ? 1.0 : 0.0;
    rep.counters["surface_components"] = double(surface_components_);
    rep.counters["sweep_ms"] = sweep_ms;
    rep.counters["cut_apply_ms"] = apply_ms;
    return rep;
  }

  void saveCheckpoint() override {
    saved_state_ = state_;
    saved_time_ = time_;
    saved_cuts_ = cuts_done_;
  }
  void restoreCheckpoint() override {
    // A checkpoint taken before the cut cannot be restored after it (the topology changed); the guard then
    // retries from the current state, which the runner treats like a restored one.
    time_ = saved_time_;
    if (saved_cuts_ == cuts_done_) {
      state_ = saved_state_;
      backend_->setState(state_);
    }
  }
  void scaleTimeStep(double factor) override {
    if (factor > 0 && std::isfinite(factor)) substep_scale_ /= factor;
  }
  void currentPositions(std::vector<Vec3d>& out) const override {
    out.resize(state_.positions.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3d(state_.positions[i]);
  }
  // Translation skinning: v = v0 + sum_j w_j (x_j - c_j) over the vertex's bound spheres.
  bool currentSurface(TriangleMesh& out) const override {
    out = rest_surface_;
    const int k = skin_.k;
    for (std::size_t v = 0; v < out.vertices.size(); ++v) {
      Vec3d d;
      for (int j = 0; j < k; ++j) {
        const int s = skin_.sphere[v * k + j];
        d += (Vec3d(state_.positions[s]) - spheres_.rest_centers[s]) * skin_.weight[v * k + j];
      }
      out.vertices[v] = skin_.rest_vertices[v] + d;
    }
    return true;
  }
  MemoryReport memory() const override {
    MemoryReport m = backend_->memory();
    m.host_bytes += model_.size() * (sizeof(Vec3<T>) * 3 + sizeof(T) * 4) +
                    rest_surface_.vertices.size() * sizeof(Vec3d) + rest_surface_.triangles.size() * 12;
    return m;
  }
  void cutWallTriangles(std::vector<std::uint8_t>& out) const override { out = wall_flags_; }
  // The viewer's layers: spheres, fixed spheres, the mouse grasp (host/pbd_render_layers.h), the swept
  // surfaces (applied cuts, the running stroke) and the last cut's nodal points (host/dissection_render_layers.h).
  void renderLayers(RenderLayers& out) const override {
    out = RenderLayers{};
    appendPbdSpheres(state_, out);
    appendPbdFixed(model_, state_, out);
    PbdFrameInput<T> in;
    appendMouseAttachments(mouse_, in);
    appendAttachmentLayers(in, state_, params_.xpbd, mouse_.tip(), out);
    std::vector<const SweptSurface*> swept;
    for (const SweptSurface& c : earlier_cuts_) swept.push_back(&c);
    if (!cut_applied_) swept.push_back(&swept_);
    swept.push_back(&stroke_);
    cut_layers_.update(swept, last_nodal_, earlier_cuts_.empty() ? nullptr : &earlier_cuts_.back(), spheres_);
    cut_layers_.apply(out.sphere_centres, out);
  }

  ToolSupport toolSupport() const override { return {true, true}; }
  // Grasp & drag (host/interactive_tool.h) and the mouse scalpel: each blade pose is taken back to the rest
  // configuration (restPointFromCurrent: the material point under it) and extends the stroke's swept
  // surface; Release applies the cut exactly as the scripted scalpel's end does (applyCut). A cut changes
  // the sphere indices, so it releases any grasp.
  ToolResult applyTool(const ToolEvent& e) override {
    std::vector<Vec3d> x(model_.size());
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = Vec3d(state_.positions[i]);
    if (e.kind == ToolKind::Grasp) {
      std::vector<double> r(model_.size());
      std::vector<std::uint8_t> movable(model_.size());
      for (std::size_t i = 0; i < r.size(); ++i) {
        r[i] = double(state_.radii[i]);
        movable[i] = model_.inv_mass[i] > T(0) ? 1 : 0;
      }
      return mouse_.apply(e, x, r, movable);
    }
    ToolResult res;
    res.supported = true;
    const BladePose world = bladeFromToolEvent(e);
    const BladePose rest{restPointFromCurrent(world.base, x, spheres_.rest_centers),
                         restPointFromCurrent(world.tip, x, spheres_.rest_centers)};
    if (e.phase == ToolPhase::Press || stroke_.vertices.empty()) {
      stroke_ = SweptSurface{};
      stroke_.vertices = {rest.base, rest.tip};
    } else {
      const std::size_t n = stroke_.vertices.size();
      // A blade that has not moved adds nothing (extendSweptSurface also drops zero-area triangles).
      if (norm(rest.base - stroke_.vertices[n - 2]) > 1e-9 || norm(rest.tip - stroke_.vertices[n - 1]) > 1e-9)
        extendSweptSurface(stroke_, rest);
    }
    if (e.phase == ToolPhase::Release) {
      const auto c0 = std::chrono::steady_clock::now();
      if (!stroke_.empty()) {
        applyCut(stroke_);
        res.cut_applied = true;
      } else {
        res.message = "the stroke swept no surface (the blade did not move)";
      }
      stroke_ = SweptSurface{};
      mouse_cut_ms_ += msSince(c0);
    }
    res.grasped = mouse_.held();
    return res;
  }

 private:
  BladePose blade(double t) const {
    const ToolPose pose = toolPoseAt(scalpel_, t);
    const Vec3d d = pose.direction * (0.5 * scalpel_.length / std::max(norm(pose.direction), 1e-300));
    return {pose.position - d, pose.position + d};
  }

  // (Re)builds the PBD model from spheres_; `carry` maps new sphere -> old state index (-1: new sphere), and a
  // new sphere takes its state from the nearest kept one not across `cut`.
  void rebuild(const std::vector<std::int32_t>* carry, const SweptSurface* cut = nullptr) {
    MetaballPbdOptions opt;
    opt.youngs_modulus = scene_.material.youngs_modulus;
    opt.stretch_compliance = scene_.pbd.stretch_compliance;
    opt.laplacian_compliance = scene_.pbd.laplacian_compliance;
    opt.fixed = scene_.fixed;
    opt.volume_samples = scene_.pbd.volume_preservation ? 64 : 0;
    const PbdState<T> old = state_;
    model_ = buildMetaballPbdModel<T>(spheres_, opt);
    backend_->setModel(model_);
    backend_->getState(state_);
    if (carry) {
      // Kept spheres keep their state; a new sphere takes the displacement and velocity of the nearest kept
      // sphere on its side of the cut (the nodal points it replaces moved with their neighbours).
      for (std::size_t i = 0; i < carry->size(); ++i)
        if ((*carry)[i] >= 0) {
          state_.positions[i] = old.positions[(*carry)[i]];
          state_.velocities[i] = old.velocities[(*carry)[i]];
        }
      for (std::size_t i = 0; i < carry->size(); ++i) {
        if ((*carry)[i] >= 0) continue;
        double best = std::numeric_limits<double>::infinity();
        int src = -1;
        const Vec3d c = spheres_.rest_centers[i];
        for (std::size_t j = 0; j < carry->size(); ++j) {
          if ((*carry)[j] < 0) continue;
          const double d = norm2(spheres_.rest_centers[j] - c);
          if (d < best && !(cut && segmentCrossesSweptSurface(*cut, c, spheres_.rest_centers[j]))) best = d, src = int(j);
        }
        if (src >= 0) {
          state_.positions[i] = Vec3<T>(c + (Vec3d(state_.positions[src]) - spheres_.rest_centers[src]));
          state_.velocities[i] = state_.velocities[src];
        }
      }
      backend_->setState(state_);
    }
    bindSurface();
  }

  // Binds the surface to the spheres. After a cut each vertex binds only to spheres it sees without crossing
  // any cut (no skin weight across a swept surface; host/cut_surface_state.h).
  void bindSurface() {
    const SkinBinding b = earlier_cuts_.empty() ? bindSkin(rest_surface_, spheres_, 4, scene_.file)
                                                : bindSkinAcrossCuts(surface_, spheres_, earlier_cuts_, 4, scene_.file);
    skin_ = Skin{b.k, b.rest_vertices, b.sphere, b.weight};
  }

  // The cut pipeline of section 5 for one finished swept surface (scripted or drawn with the mouse).
  void applyCut(const SweptSurface& cut) {
    ++cuts_done_;
    if (cut.empty()) return;
    mouse_.release();  // sphere indices change
    SphereCutResult r = cutSpheres(spheres_, cut);
    double rmax = 0.0;
    for (auto i : r.cut) rmax = std::max(rmax, spheres_.rest_radii[i]);
    last_points_ = r.points.size();
    last_nodal_ = r.points;
    // Earlier cuts: the new spheres are grouped and linked only on their own side of each (successive cuts).
    last_added_ = repackSpheres(r.spheres, r.points, cut, rmax, RepackOptions{}, earlier_cuts_);
    earlier_cuts_.push_back(cut);
    std::vector<std::int32_t> carry(r.kept.begin(), r.kept.end());
    carry.resize(r.spheres.size(), -1);
    // The surface: split along the swept surface whatever its shape (a partial cut leaves one closed mesh with
    // a slit), at every cut; CGAL walls (host/cut_surface_split.h).
    if (!surface_split_) surface_ = cutSurfaceState(rest_surface_);
    if (applySurfaceCut(surface_, cut).split) {
      rest_surface_ = surface_.mesh;
      wall_flags_ = surface_.wall;
      surface_split_ = true;
    }
    surface_components_ = analyzeMesh(rest_surface_).components;
    spheres_ = std::move(r.spheres);
    sphere_components_ = sphereGraphComponents(spheres_);
    rebuild(&carry, &cut);
  }

  Scene scene_;
  BackendKind kind_;
  ToolSpec scalpel_;
  bool has_scalpel_ = false;
  MetaballModel spheres_;
  TriangleMesh rest_surface_;
  CutSurfaceState surface_;  // the split surface with its wall flags and binding probes (after the first split)
  struct Skin {  // translation skinning slots v * k + j (sphere index into spheres_, weight)
    int k = 0;
    std::vector<Vec3d> rest_vertices;
    std::vector<std::int32_t> sphere;
    std::vector<double> weight;
  } skin_;
  PbdModel<T> model_;
  std::unique_ptr<PbdBackend<T>> backend_;
  PbdStepParams<T> params_;
  PbdState<T> state_, saved_state_;
  SweptSurface swept_;
  std::size_t pending_ = 0, last_points_ = 0, last_added_ = 0;
  bool cut_applied_ = false, surface_split_ = false;
  int cuts_done_ = 0, saved_cuts_ = 0;  // cuts applied (scripted and mouse)
  int surface_components_ = 1, sphere_components_ = 1;
  std::vector<std::uint8_t> wall_flags_;  // per rest_surface_ triangle: 1 = cut wall
  PbdMouseGrasp mouse_;                   // the viewer's grasp
  SweptSurface stroke_;                   // the mouse scalpel's stroke so far (rest configuration)
  std::vector<SweptSurface> earlier_cuts_;  // every cut applied so far (rest configuration)
  double mouse_cut_ms_ = 0.0;
  NodalPoints last_nodal_;                // the last cut's nodal points (rest configuration), for the viewer
  mutable CutLayerBinding cut_layers_;    // renderLayers' bindings (rebuilt when the cut geometry changes)
  int base_substeps_ = 4;
  double substep_scale_ = 1.0;
  double time_ = 0, saved_time_ = 0;
};

}  // namespace

std::unique_ptr<SimulationModel> makeDissectionSimulation(const Scene& scene, BackendKind backend, Precision precision) {
  if (precision == Precision::Float64) return std::make_unique<DissectionSimulation<double>>(scene, backend);
  return std::make_unique<DissectionSimulation<float>>(scene, backend);
}

}  // namespace inc
