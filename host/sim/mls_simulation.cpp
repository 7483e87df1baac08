// MlsSimulation: an MlsSolver behind the SimulationModel interface, assembled from a compiled scene.
#include "host/sim/mls_simulation.h"
#include "host/backends/solver_factory.h"
#include "host/compiled/scene_colliders.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "host/assembly/particle_sampling.h"
#include "host/io/mesh.h"
#include "model/frame_budget.h"
#include "model/input_error.h"
#include "model/mls_solver.h"

namespace inc {

namespace {

// Tool tip position at time t: piecewise linear over the keyframes, held constant outside them.
Vec3d toolPosition(const ToolSpec& tool, double t) {
  const auto& k = tool.path;
  if (t <= k.front().t) return k.front().position;
  for (std::size_t i = 1; i < k.size(); ++i)
    if (t <= k[i].t) {
      const double span = k[i].t - k[i - 1].t;
      const double a = span > 0 ? (t - k[i - 1].t) / span : 1.0;
      return k[i - 1].position + (k[i].position - k[i - 1].position) * a;
    }
  return k.back().position;
}

// A grasper holds the free particles within its radius of its first keyframe and carries them along its path.
struct Grasp {
  std::size_t tool = 0;
  std::vector<std::int32_t> particles;
};

bool insideBox(const Vec3d& p, const FixedRegion& r) {
  return p.x >= r.min.x && p.x <= r.max.x && p.y >= r.min.y && p.y <= r.max.y && p.z >= r.min.z && p.z <= r.max.z;
}

class MlsSimulation final : public SimulationModel {
 public:
  MlsSimulation(std::unique_ptr<MlsSolver> solver, const CompiledScene& scene, const MlsBuildInput& in)
      : solver_(std::move(solver)), fixed_substeps_(scene.solver.substeps), tools_(scene.tools) {
    // For the viewer's layers: which particles are fixed, the masses (as makeMlsModel sets them) and gravity.
    gravity_ = in.gravity;
    collider_mesh_ = colliderMeshAround(scene.colliders, in.rest_positions);
    fixed_.assign(in.rest_positions.size(), 0);
    masses_.resize(in.rest_positions.size());
    for (std::size_t i = 0; i < masses_.size(); ++i) {
      masses_[i] = in.masses.empty() ? in.material.density_kg_m3 * in.spacing * in.spacing * in.spacing : in.masses[i];
      fixed_[i] = !in.kinds.empty() && in.kinds[i] == kMlsFixed ? 1 : 0;
    }
    // Refuse an unstable fixed substep count now (bad input), not in the middle of a run.
    planMlsSubsteps(scene.solver.frame_dt, solver_->stableTimeStep(), solver_->safety(), fixed_substeps_, scene.file,
                    "solver.substeps");
    // The frame budget: a frame that would need more substeps is refused (advance() reports why), so that no frame
    // runs for minutes; a fixed count above it is a contradiction in the scene.
    max_substeps_ = scene.solver.max_substeps;
    solver_->setMaxSubsteps(frameSubstepLimit(solver_->size(), max_substeps_));
    checkFixedSubstepsFit(fixed_substeps_, solver_->size(), max_substeps_, scene.file);
    const std::vector<Vec3d> rest = solver_->restPositions();
    for (std::size_t k = 0; k < tools_.size(); ++k) {
      const ToolSpec& tool = tools_[k];
      const std::string key = "tools[" + std::to_string(k) + "]";
      if (tool.kind != "grasper") continue;  // probes (contact) and scalpels (cutting) belong to other models
      if (tool.path.empty()) throw InputError(scene.file, key + ".path", "a grasper needs at least one keyframe");
      if (!(std::isfinite(tool.radius) && tool.radius > 0))
        throw InputError(scene.file, key + ".radius_m", "must be > 0");
      for (std::size_t p = 1; p < tool.path.size(); ++p)
        if (!(tool.path[p].t >= tool.path[p - 1].t))
          throw InputError(scene.file, key + ".path", "keyframes must be sorted by t_s");
      Grasp g;
      g.tool = k;
      const Vec3d at = tool.path.front().position;
      for (std::size_t i = 0; i < rest.size(); ++i)
        if (norm2(rest[i] - at) <= tool.radius * tool.radius) g.particles.push_back(std::int32_t(i));
      if (g.particles.empty())
        throw InputError(scene.file, key, "the grasper's first keyframe holds no particle within radius_m of it");
      grasps_.push_back(std::move(g));
    }
  }

  std::string name() const override { return "mls"; }
  BackendKind backend() const override { return solver_->backend(); }
  std::size_t particleCount() const override { return solver_->size(); }

  FrameReport advance(double frame_dt) override {
    // Graspers: their particles reach the tool's displacement at the end of this frame.
    const double t1 = time_ + frame_dt;
    for (const Grasp& g : grasps_) {
      const ToolSpec& tool = tools_[g.tool];
      const Vec3d d = toolPosition(tool, t1) - tool.path.front().position;
      solver_->setPrescribed(g.particles, std::vector<Vec3d>(g.particles.size(), d));
    }
    // The mouse grasp: held particles are prescribed to their displacement at the grasp plus the tip's
    // motion since, reached at the end of this frame (the nodes are pinned to the tool and dragged).
    if (!mouse_ids_.empty()) {
      std::vector<Vec3d> targets(mouse_ids_.size());
      for (std::size_t k = 0; k < mouse_ids_.size(); ++k) targets[k] = mouse_u0_[k] + (mouse_tip_ - mouse_tip0_);
      solver_->setPrescribed(mouse_ids_, targets);
    }
    const MlsFrameStats st = solver_->advance(frame_dt, fixed_substeps_);
    if (st.totals.finite) time_ = t1;
    FrameReport r;
    r.substeps = st.substeps;
    r.dt = st.dt;
    r.stages = {
        {"integrate", st.ms_integrate}, {"stress", st.ms_stress}, {"forces", st.ms_forces}, {"reduce", st.ms_reduce}};
    r.kinetic_energy = st.totals.kinetic_energy;
    r.elastic_energy = st.totals.elastic_energy;
    r.potential_energy = st.totals.potential_energy;
    r.max_displacement = st.totals.max_displacement;
    r.finite = st.totals.finite;
    r.failure_stage = st.totals.bad_stage;
    r.failure_particle = st.totals.first_bad;
    if (st.substeps_needed > 0) refuse(r, st.substeps_needed);
    const MlsModelStats& m = solver_->modelStats();
    r.counters["stable_dt_s"] = solver_->stableTimeStep();                 // rest state, safety 1
    r.counters["current_stable_dt_s"] = solver_->currentStableTimeStep();  // at the frame's end deformation
    r.counters["stiffening"] = st.totals.stiffening;
    r.counters["regularised_particles"] = double(m.regularised);
    r.counters["few_neighbours"] = double(m.few_neighbors);
    r.counters["coplanar_neighbourhoods"] = double(m.coplanar);
    r.counters["collinear_neighbourhoods"] = double(m.collinear);
    r.counters["ill_conditioned"] = double(m.ill_conditioned);
    r.counters["isolated_particles"] = double(m.isolated);
    r.counters["min_neighbours"] = double(m.min_neighbors);
    r.counters["mean_neighbours"] = m.mean_neighbors;
    r.counters["max_condition"] = m.max_condition;
    double grasped = 0;
    for (const Grasp& g : grasps_) grasped += double(g.particles.size());
    grasped += double(mouse_ids_.size());
    r.counters["grasped_particles"] = grasped;
    return r;
  }

  // A frame the solver refused for the frame budget: what it needed, the limit and the keys to change.
  void refuse(FrameReport& r, double needed) const {
    refuseFrame(r, substepLimitReason("MLS substeps", needed, solver_->maxSubsteps(),
                                      frameSubstepLimitRule(solver_->size(), max_substeps_),
                                      std::string(kMlsSubstepKeys) + (fixed_substeps_ > 0 ? ", solver.substeps" : "")));
  }

  void saveCheckpoint() override {
    solver_->saveCheckpoint();
    saved_time_ = time_;
  }
  void restoreCheckpoint() override {
    solver_->restoreCheckpoint();
    time_ = saved_time_;
  }

  void scaleTimeStep(double factor) override {
    if (!(factor > 0) || !std::isfinite(factor)) return;
    solver_->setSafety(solver_->safety() * factor);
    if (fixed_substeps_ > 0) fixed_substeps_ = int(std::ceil(double(fixed_substeps_) / factor));
  }

  void currentPositions(std::vector<Vec3d>& out) const override { solver_->positions(out); }
  MemoryReport memory() const override { return solver_->memory(); }

  ToolSupport toolSupport() const override { return {true, false}; }
  // Grasp & drag: Press pins the particles within radius_m of the tip (fixed ones stay fixed), Drag moves
  // their prescribed displacement with the tip, Release returns them to free dynamics. No cutting here.
  ToolResult applyTool(const ToolEvent& e) override {
    if (e.kind != ToolKind::Grasp) return SimulationModel::applyTool(e);
    if (!isFinite(e.tip)) throw InputError("tool", "tip", "must be finite");
    ToolResult r;
    r.supported = true;
    if (e.phase == ToolPhase::Press || e.phase == ToolPhase::Release) {
      if (!mouse_ids_.empty()) solver_->release(mouse_ids_);
      mouse_ids_.clear();
      mouse_u0_.clear();
    }
    if (e.phase == ToolPhase::Press) {
      if (!(e.radius_m > 0) || !std::isfinite(e.radius_m)) throw InputError("tool", "radius_m", "must be > 0");
      std::vector<Vec3d> x, u;
      solver_->positions(x);
      solver_->displacements(u);
      for (std::size_t i = 0; i < x.size(); ++i)
        if (norm2(x[i] - e.tip) <= e.radius_m * e.radius_m) {
          mouse_ids_.push_back(std::int32_t(i));
          mouse_u0_.push_back(u[i]);
        }
      mouse_tip0_ = mouse_tip_ = e.tip;
      if (mouse_ids_.empty()) r.message = "no particle within reach of the tip";
    } else if (e.phase == ToolPhase::Drag) {
      mouse_tip_ = e.tip;
    }
    r.grasped = int(mouse_ids_.size());
    return r;
  }

  // The viewer's layers. Every particle is an MLS nodal point. Fixed particles, and the particles a tool holds
  // (scripted graspers, the mouse), are pinned: what pins particle i applies F_i = m_i a_i - f_i - m_i g,
  // with f_i the body's elastic force on it (MlsSolver::forces at the current displacement), taken
  // quasi-statically (a_i = 0): F_i = -(f_i + m_i g). The elastic forces sum to zero, so at rest the F_i of
  // all supports and tools carry the body's weight. A tool's arrow at its tip is the tissue's reaction,
  // -sum F_i over its particles.
  void renderLayers(RenderLayers& out) const override {
    out = RenderLayers{};
    out.colliders = collider_mesh_;
    std::vector<Vec3d> x, f;
    solver_->positions(x);
    solver_->forces(f);
    if (f.size() != x.size() || masses_.size() != x.size()) return;
    out.nodal_points = x;
    const auto pinned = [&](std::size_t i) { return (f[i] + gravity_ * masses_[i]) * -1.0; };
    for (std::size_t i = 0; i < x.size(); ++i)
      if (fixed_[i]) {
        out.fixed_ids.push_back(std::int32_t(i));
        out.fixed_points.push_back(x[i]);
        out.forces.push_back({x[i], pinned(i), ForceArrowKind::Particle});
      }
    const auto held = [&](const std::vector<std::int32_t>& ids, const Vec3d& tip) {
      Vec3d total;
      bool any = false;
      for (std::int32_t id : ids) {
        const std::size_t i = std::size_t(id);
        if (fixed_[i]) continue;  // a fixed particle stays fixed under a tool
        const Vec3d F = pinned(i);
        out.held_ids.push_back(id);
        out.held_points.push_back(x[i]);
        out.forces.push_back({x[i], F, ForceArrowKind::Particle});
        total += F;
        any = true;
      }
      if (any) out.forces.push_back({tip, total * -1.0, ForceArrowKind::Tool});
    };
    for (const Grasp& g : grasps_) held(g.particles, toolPosition(tools_[g.tool], time_));
    held(mouse_ids_, mouse_tip_);
  }

 private:
  Vec3d gravity_;                        // m/s^2
  std::vector<double> masses_;           // kg
  TriangleMesh collider_mesh_;           // the scene's colliders drawn around the body (RenderLayers::colliders)
  std::vector<std::uint8_t> fixed_;      // 1: in a fixed region
  std::vector<std::int32_t> mouse_ids_;  // the viewer's grasp: held particles
  std::vector<Vec3d> mouse_u0_;          // their displacements at the grasp (m)
  Vec3d mouse_tip0_, mouse_tip_;         // tip at the grasp and now (m)
  std::unique_ptr<MlsSolver> solver_;
  int fixed_substeps_ = 0;
  int max_substeps_ = 0;  // solver.max_substeps (0: the frame budget's automatic limit)
  std::vector<ToolSpec> tools_;
  std::vector<Grasp> grasps_;
  double time_ = 0.0, saved_time_ = 0.0;  // s, simulated time (tool paths are functions of it)
};

}  // namespace

MlsBuildInput mlsSolverSettings(const CompiledScene& scene) {
  MlsBuildInput in;
  in.source = scene.file;
  in.support_factor = scene.mls.support_factor;
  in.condition_limit = scene.mls.condition_limit;
  in.material = MlsMaterial{scene.material, scene.mls.volume_preservation, scene.mls.volume_stiffness};
  in.gravity = scene.solver.gravity;
  in.safety = scene.solver.safety;
  return in;
}

MlsBuildInput mlsBuildInputFromScene(const CompiledScene& scene) {
  MlsBuildInput in = mlsSolverSettings(scene);
  const GeometrySpec& g = scene.geometry;
  if (g.kind == GeometrySpec::Kind::Mesh) {
    if (!(std::isfinite(g.mesh_scale) && g.mesh_scale > 0))
      throw InputError(scene.file, "geometry.mesh_scale", "must be a positive number");
    if (!(std::isfinite(g.spacing) && g.spacing > 0))
      throw InputError(scene.file, "geometry.spacing_m", "must be a positive number");
    TriangleMesh mesh = loadMesh(g.mesh_path);
    for (auto& v : mesh.vertices) v = v * g.mesh_scale;
    in.rest_positions = sampleMesh(mesh, LatticeSpec{g.spacing, g.jitter, g.seed});
    if (in.rest_positions.empty())
      throw InputError(scene.file, "geometry.spacing_m",
                       "the mesh sampled to no particle (spacing larger than the body?)");
  } else {
    in.rest_positions = sampleGeometry(g, scene.file);
  }
  in.spacing = g.spacing;
  in.kinds.assign(in.rest_positions.size(), kMlsFree);
  for (std::size_t f = 0; f < scene.fixed.size(); ++f) {
    const FixedRegion& r = scene.fixed[f];
    if (!isFinite(r.min) || !isFinite(r.max) || r.min.x > r.max.x || r.min.y > r.max.y || r.min.z > r.max.z)
      throw InputError(scene.file, "fixed[" + std::to_string(f) + "]", "min_m must be finite and <= max_m per axis");
    for (std::size_t i = 0; i < in.rest_positions.size(); ++i)
      if (insideBox(in.rest_positions[i], r)) in.kinds[i] = kMlsFixed;
  }
  return in;
}

std::unique_ptr<SimulationModel> makeMlsSimulation(const CompiledScene& scene, BackendKind resolved,
                                                   Precision precision) {
  if (resolved == BackendKind::Auto)
    throw InputError(scene.file, "solver.backend", "makeMlsSimulation needs a resolved backend (cpu or cuda)");
  if (scene.solver.substeps < 0) throw InputError(scene.file, "solver.substeps", "must be >= 0");
  const MlsBuildInput in = mlsBuildInputFromScene(scene);
  checkCollidersClear(scene, in.rest_positions, "particles");
  std::unique_ptr<MlsSolver> solver = makeMlsSolver(in, resolved, precision);
  const StaticColliders colliders = staticColliders(scene.colliders);
  solver->setStaticColliders(colliders.planes, colliders.boxes, 0.5 * in.spacing);
  return std::make_unique<MlsSimulation>(std::move(solver), scene, in);
}

}  // namespace inc
