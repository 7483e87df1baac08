// PBD metaball organ as a SimulationModel: sphere fill (lattice or packer), constraint model, skinned surface, tools,
// frame reports.
#include "host/sim/metaball_simulation.h"
#include "host/backends/solver_factory.h"
#include "host/compiled/material_checks.h"
#include "host/compiled/scene_colliders.h"
#include "host/io/triangle_bvh.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "cpu_fallback/skinning_cpu.h"
#include "host/assembly/metaball_packing.h"
#include "host/assembly/particle_sampling.h"
#include "host/assembly/pbd_builders.h"
#include "host/assembly/scene_surface.h"
#include "host/assembly/skin_binding.h"
#include "host/assembly/sphere_graph_repair.h"
#include "host/io/mesh.h"
#include "host/sim/grasper.h"
#include "host/sim/interactive_tool.h"
#include "host/sim/pbd_organ_settings.h"
#include "host/sim/pbd_render_layers.h"
#include "model/frame_budget.h"
#include "model/input_error.h"
#include "model/pbd_model.h"
#include "physics/pbd_rotation.h"

namespace inc {

namespace {

constexpr double kRadiusFactor = 0.75;  // sphere radius / lattice spacing
// Widest gap between two balls (fraction of the spacing) that a straggler's link may cross: corner neighbours
// (gap 0.23) and next-but-one cells along an axis (0.5) qualify.
constexpr double kStragglerReach = 1.0;
constexpr int kDefaultSubsteps = 4;
// Longest PBD substep h allowed: gravity moves a free sphere by |g| h^2 per substep before projection; past a
// tenth of the lattice spacing the projection's corrections turn into large velocities (v = dx / h) and
// one-substep frames were measured to fling a 40 mm bar by 0.11-1.5 m (tests/support/stability_matrix.h).
constexpr double kMaxSagPerSubstep = 0.1;  // fraction of geometry.spacing

// Spheres the fill could not join to the rest of their mesh piece are dropped (their mass moved to neighbours); past
// this fraction of the fill the body the model simulates is no longer the mesh the user gave.
constexpr double kMaxDroppedFraction = 0.05;

void refuseLargeDrops(int dropped, int filled, const std::string& file, const std::string& key,
                      const std::string& remedy) {
  if (dropped <= kMaxDroppedFraction * filled) return;
  throw InputError(file, key,
                   std::to_string(dropped) + " of the " + std::to_string(filled) +
                       " spheres filled lie in parts of the mesh too thin for them to be joined to the rest (a sphere "
                       "without constraints would fall away); " +
                       remedy);
}

double maxPbdSubstep(const CompiledScene& scene) {
  const double g = norm(scene.solver.gravity);
  return g > 0 ? std::sqrt(kMaxSagPerSubstep * scene.geometry.spacing / g) : 1.0e300;
}

// Links between overlapping spheres through a hash grid of cell 2 r_max (each pair tested once).
void linkOverlapping(MetaballModel& mb) {
  const std::size_t n = mb.size();
  double rmax = 0;
  for (double r : mb.rest_radii) rmax = std::max(rmax, r);
  const double cell = 2.0 * rmax;
  auto key = [&](const Vec3d& p) {
    const long long i = (long long)std::floor(p.x / cell), j = (long long)std::floor(p.y / cell),
                    k = (long long)std::floor(p.z / cell);
    return std::make_tuple(i, j, k);
  };
  struct Hash {
    std::size_t operator()(const std::tuple<long long, long long, long long>& t) const {
      return std::size_t(std::get<0>(t) * 73856093LL ^ std::get<1>(t) * 19349663LL ^ std::get<2>(t) * 83492791LL);
    }
  };
  std::unordered_map<std::tuple<long long, long long, long long>, std::vector<std::int32_t>, Hash> grid;
  for (std::size_t i = 0; i < n; ++i) grid[key(mb.rest_centers[i])].push_back(std::int32_t(i));
  for (std::size_t i = 0; i < n; ++i) {
    const auto [a, b, c] = key(mb.rest_centers[i]);
    std::vector<std::int32_t> found;
    for (long long da = -1; da <= 1; ++da)
      for (long long db = -1; db <= 1; ++db)
        for (long long dc = -1; dc <= 1; ++dc) {
          auto it = grid.find(std::make_tuple(a + da, b + db, c + dc));
          if (it == grid.end()) continue;
          for (std::int32_t j : it->second) {
            if (std::size_t(j) <= i) continue;
            const double d = norm(mb.rest_centers[i] - mb.rest_centers[j]);
            if (d < mb.rest_radii[i] + mb.rest_radii[j] && d > 0) found.push_back(j);
          }
        }
    std::sort(found.begin(), found.end());
    for (std::int32_t j : found) {
      mb.links.push_back({std::int32_t(i), j});
      mb.link_rest_lengths.push_back(norm(mb.rest_centers[i] - mb.rest_centers[j]));
    }
  }
}

template <typename T>
class MetaballSimulation final : public SimulationModel {
 public:
  MetaballSimulation(const CompiledScene& scene, BackendKind backend) : scene_(scene) {
    const std::string& f = scene.file;
    if (scene.pbd.iterations < 1) throw InputError(f, "pbd.iterations", "must be >= 1");
    if (scene.solver.substeps < 0) throw InputError(f, "solver.substeps", "must be >= 0");
    validateMaterial(scene.material, f);  // a scene built in code has not met the loader's check
    params_ = pbdOrganParams<T>(scene);
    max_substep_s_ = maxPbdSubstep(scene);
    const double fdt = scene.solver.frame_dt;
    if (scene.solver.substeps > 0 && fdt / scene.solver.substeps > max_substep_s_) {
      const int need = int(std::ceil(fdt / max_substep_s_ - 1e-9));
      throw InputError(f, "solver.substeps",
                       std::to_string(scene.solver.substeps) + " substep(s) of a " + std::to_string(fdt) +
                           " s frame exceed the longest stable PBD substep here, " + std::to_string(max_substep_s_) +
                           " s (gravity sag per substep under a tenth of geometry.spacing): use at least " +
                           std::to_string(need) + ", or 0 to choose automatically");
    }
    base_substeps_ = scene.solver.substeps > 0 ? scene.solver.substeps : kDefaultSubsteps;
    auto_substeps_ = scene.solver.substeps == 0;
    max_substeps_ = scene.solver.max_substeps;

    const MetaballModel mb = buildSceneMetaballs(scene, &fill_note_);
    checkCollidersClear(scene, mb.rest_centers, "sphere centres");
    collider_mesh_ = colliderMeshAround(scene.colliders, mb.rest_centers);
    MetaballPbdOptions opt = pbdOrganOptions(scene);
    rest_surface_ = sceneSurfaceMesh(scene);
    std::shared_ptr<const pack::SurfaceDistance> depth;
    if (!scene.colliders.empty()) {
      depth = std::make_shared<const pack::SurfaceDistance>(rest_surface_);
      opt.surface_depth = [depth](const Vec3d& x) { return -depth->signedDistance(x).distance; };
    }
    model_ = buildMetaballPbdModel<T>(mb, opt);
    checkFixedSubstepsFit(scene.solver.substeps, model_.size(), max_substeps_, f);
    // The organ's surface rides on the spheres (linear-blend skinning, k = 4 nearest spheres).
    skin_ = skinArrays<T>(bindSkin(rest_surface_, mb, std::min<int>(4, int(mb.size())), f));
    backend_ = makePbdBackend<T>(backend);
    backend_->setModel(model_);
    backend_->getState(state_);

    for (const ToolSpec& t : scene.tools) {
      if (t.path.empty()) throw InputError(f, "tools." + t.name + ".path", "needs at least one keyframe");
      if (t.kind == "grasper")
        graspers_.emplace_back(t, t.radius + scene.geometry.spacing, 1.0e-6);
      else if (t.kind == "probe")
        probes_.push_back(t);
    }
    movable_.resize(model_.size());
    for (std::size_t i = 0; i < model_.size(); ++i) movable_[i] = model_.inv_mass[i] > T(0) ? 1 : 0;
    saveCheckpoint();
  }

  std::string name() const override { return "pbd_metaballs"; }
  BackendKind backend() const override { return backend_->kind(); }
  std::size_t particleCount() const override { return model_.size(); }
  std::string buildNote() const override { return fill_note_; }

  FrameReport advance(double frame_dt) override {
    FrameReport rep;
    const double t0 = time_, t1 = time_ + frame_dt;
    PbdFrameInput<T> in;
    for (Grasper& g : graspers_) {
      if (g.holding() && t0 >= g.releaseTime()) g.release();
      if (!g.holding() && !g.finished() && t0 >= g.closeTime() && t0 < g.releaseTime()) {
        std::vector<Vec3d> c(model_.size());
        std::vector<double> r(model_.size());
        for (std::size_t i = 0; i < model_.size(); ++i) {
          c[i] = Vec3d(state_.positions[i]);
          r[i] = double(state_.radii[i]);
        }
        g.grasp(toolPoseAt(g.tool(), t0).position, c, r, movable_);
      }
      appendGrasperInput(g, t0, t1, in);
    }
    appendProbeInputs(probes_, t0, t1, in);
    appendMouseAttachments(mouse_, in);
    PbdStepParams<T> p = params_;
    p.frame_dt = T(frame_dt);
    p.substeps = substeps();
    // Automatic substepping also covers frames longer than the scene's (a slowed-down viewer, a retry).
    if (auto_substeps_)
      p.substeps = std::max(p.substeps, int(std::min(std::ceil(frame_dt / max_substep_s_ - 1e-9), 2e9)));
    // The frame budget (model/frame_budget.h): a frame of more substeps is refused, not run for minutes.
    if (std::string why = pbdSubstepRefusal(p.substeps, model_.size(), max_substeps_); !why.empty()) {
      refuseFrame(rep, std::move(why));
      return rep;
    }
    const PbdFrameStats st = backend_->advanceFrame(p, in);
    backend_->getState(state_);
    mouse_.frameDone();
    time_ = t1;

    rep.substeps = p.substeps;
    rep.dt = frame_dt / p.substeps;
    rep.stages = st.stages;
    rep.finite = st.finite;
    if (!st.finite) {
      rep.failure_stage = "pbd";
      rep.failure_particle = st.failure_particle;
    }
    energies(rep, double(p.frame_dt) / p.substeps);
    int grasped = 0;
    for (const Grasper& g : graspers_) grasped += int(g.grasped().size());
    grasped += mouse_.held();
    rep.counters["residual_max_m"] = st.residual_max;
    rep.counters["residual_rms_m"] = st.residual_rms;
    rep.counters["colors"] = st.colors;
    rep.counters["iterations"] = st.iterations;
    rep.counters["substeps"] = p.substeps;
    rep.counters["grasped"] = grasped;
    rep.counters["volume_active"] = st.volume_active;
    rep.counters["max_radius_ratio"] = st.max_radius_ratio;
    return rep;
  }

  void saveCheckpoint() override {
    saved_state_ = state_;
    saved_time_ = time_;
    saved_graspers_ = graspers_;
  }
  ToolSupport toolSupport() const override { return {true, false}; }
  // Grasp & drag with the mouse (host/sim/interactive_tool.h); cutting belongs to the dissection model.
  ToolResult applyTool(const ToolEvent& e) override {
    if (e.kind != ToolKind::Grasp) return SimulationModel::applyTool(e);
    std::vector<Vec3d> c(model_.size());
    std::vector<double> r(model_.size());
    for (std::size_t i = 0; i < model_.size(); ++i) {
      c[i] = Vec3d(state_.positions[i]);
      r[i] = double(state_.radii[i]);
    }
    return mouse_.apply(e, c, r, movable_);
  }
  void restoreCheckpoint() override {
    state_ = saved_state_;
    time_ = saved_time_;
    graspers_ = saved_graspers_;
    backend_->setState(state_);
  }
  void scaleTimeStep(double factor) override {
    if (factor > 0 && std::isfinite(factor)) substep_scale_ /= factor;
  }
  void currentPositions(std::vector<Vec3d>& out) const override {
    out.resize(state_.positions.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3d(state_.positions[i]);
  }
  // Skinned with each sphere's translation and its shape-matching rotation (identity when the model keeps none).
  bool currentSurface(TriangleMesh& out) const override {
    const int n = int(model_.size());
    rotations_.resize(model_.size());
    skinned_.resize(skin_.rest_vertices.size());
    cpu::quatsToMatricesCpu<T>(n, state_.rotations.data(), rotations_.data());
    cpu::skinSurfaceCpu<T>(skin_.view(), state_.positions.data(), rotations_.data(), skinned_.data());
    out.vertices.resize(skinned_.size());
    for (std::size_t v = 0; v < skinned_.size(); ++v) out.vertices[v] = Vec3d(skinned_[v]);
    out.triangles = rest_surface_.triangles;
    return true;
  }
  // The viewer's layers: every sphere, the fixed ones, and per grasp (scripted graspers, the mouse) the held
  // spheres, the attachment forces on them and the reaction on the tool (host/sim/pbd_render_layers.h).
  void renderLayers(RenderLayers& out) const override {
    out = RenderLayers{};
    out.colliders = collider_mesh_;
    appendPbdSpheres(state_, out);
    appendPbdFixed(model_, state_, out);
    PbdFrameInput<T> all;
    for (const Grasper& g : graspers_) {
      if (!g.holding()) continue;
      const Vec3d tip = toolPoseAt(g.tool(), time_).position;
      PbdFrameInput<T> one;
      g.appendAttachments(tip, tip, one);
      appendAttachmentLayers(one, state_, params_.xpbd, tip, out);
      g.appendAttachments(tip, tip, all);
    }
    // The mouse's spheres, less those a scripted grasper holds (as the frame's input was assembled).
    const std::size_t scripted = all.attach_ids.size();
    appendMouseAttachments(mouse_, all);
    PbdFrameInput<T> mouse;
    mouse.attach_ids.assign(all.attach_ids.begin() + std::ptrdiff_t(scripted), all.attach_ids.end());
    mouse.attach_to.assign(all.attach_to.begin() + std::ptrdiff_t(scripted), all.attach_to.end());
    mouse.attach_compliance.assign(all.attach_compliance.begin() + std::ptrdiff_t(scripted),
                                   all.attach_compliance.end());
    appendAttachmentLayers(mouse, state_, params_.xpbd, mouse_.tip(), out);
  }
  MemoryReport memory() const override {
    MemoryReport m = backend_->memory();
    m.host_bytes += model_.size() * (sizeof(Vec3<T>) * 3 + sizeof(T) * 4) +
                    skin_.rest_vertices.size() * (sizeof(Vec3<T>) * 2 + skin_.k * (sizeof(T) + 4)) +
                    rest_surface_.triangles.size() * 12;
    return m;
  }

 private:
  int substeps() const { return std::max(1, int(std::ceil(base_substeps_ * substep_scale_ - 1e-9))); }

  // Kinetic, gravity potential (relative to rest) and compliance energy of the stretch and Laplacian
  // constraints (sum |C|^2 / 2 alpha, the XPBD potential), and the max displacement from rest.
  void energies(FrameReport& rep, double /*dt*/) const {
    double ke = 0, pe = 0, disp = 0;
    const Vec3d g = scene_.solver.gravity;
    for (std::size_t i = 0; i < model_.size(); ++i) {
      const Vec3d x(state_.positions[i]), x0(model_.rest_positions[i]), v(state_.velocities[i]);
      const double m = double(model_.masses[i]);
      ke += 0.5 * m * norm2(v);
      pe -= m * dot(g, x - x0);
      disp = std::max(disp, norm(x - x0));
    }
    double el = 0;
    for (const PbdConstraintBlock<T>& b : model_.blocks) {
      if (!b.solve) continue;
      for (std::size_t c = 0; c < b.count(); ++c) {
        const double a = double(b.compliance[c]);
        if (!(a > 0)) continue;
        const std::int32_t s0 = b.offsets[c], s1 = b.offsets[c + 1];
        if (b.kind == PbdConstraintKind::Distance) {
          const double cv =
              norm(Vec3d(state_.positions[b.ids[s0]]) - Vec3d(state_.positions[b.ids[s0 + 1]])) - double(b.rest[c]);
          el += 0.5 * cv * cv / a;
        } else if (b.kind == PbdConstraintKind::Laplacian) {
          Vec3d mean;
          for (std::int32_t s = s0 + 1; s < s1; ++s) mean += Vec3d(state_.positions[b.ids[s]]);
          mean *= 1.0 / double(s1 - s0 - 1);
          const Mat3<T> rot = pbd::quatToMatrix(state_.rotations[b.ids[s0]]);
          const Vec3d cv = Vec3d(state_.positions[b.ids[s0]]) - mean - Vec3d(rot * b.rest_vec[c]);
          el += 0.5 * norm2(cv) / a;
        }
      }
    }
    rep.kinetic_energy = ke;
    rep.potential_energy = pe;
    rep.elastic_energy = el;
    rep.max_displacement = disp;
  }

  CompiledScene scene_;
  std::string fill_note_;  // how the spheres were filled and joined (buildSceneMetaballs)
  PbdModel<T> model_;
  std::unique_ptr<PbdBackend<T>> backend_;
  PbdStepParams<T> params_;
  PbdState<T> state_, saved_state_;
  std::vector<Grasper> graspers_, saved_graspers_;
  std::vector<ToolSpec> probes_;
  PbdMouseGrasp mouse_;  // the viewer's grasp (not part of checkpoints: the user holds it)
  std::vector<std::uint8_t> movable_;
  TriangleMesh rest_surface_;
  TriangleMesh collider_mesh_;  // the scene's colliders drawn around the organ (RenderLayers::colliders)
  SkinArrays<T> skin_;
  mutable std::vector<Mat3<T>> rotations_;  // scratch for currentSurface
  mutable std::vector<Vec3<T>> skinned_;
  int base_substeps_ = kDefaultSubsteps;
  bool auto_substeps_ = true;
  int max_substeps_ = 0;  // solver.max_substeps (0: the frame budget's automatic limit)
  double max_substep_s_ = 1.0e300;
  double substep_scale_ = 1.0;
  double time_ = 0, saved_time_ = 0;
};

}  // namespace

MetaballModel buildSceneMetaballs(const CompiledScene& scene, std::string* fill_note) {
  const GeometrySpec& g = scene.geometry;
  const std::string& f = scene.file;
  if (!(std::isfinite(g.spacing) && g.spacing > 0))
    throw InputError(f, "geometry.spacing_m", "must be a positive number");
  validateMaterial(scene.material, f);
  if (scene.pbd.target_spheres > 0) {
    // The packer (paper, section 4): overlapping spheres fitted to the closed surface, masses from power cells.
    PackingOptions o;
    o.target_spheres = scene.pbd.target_spheres;
    o.density_kg_m3 = scene.material.density_kg_m3;
    o.mesh_key = g.kind == GeometrySpec::Kind::Mesh ? "geometry.mesh" : "geometry";
    PackedOrgan packed = packOrgan(sceneSurfaceMesh(scene), o, scene.file);
    refuseLargeDrops(packed.report.dropped, packed.report.spheres + packed.report.dropped, f, "pbd.target_spheres",
                     "raise it or smooth the mesh's thin parts");
    if (fill_note) *fill_note = "packed: " + describePack(packed.report);
    return std::move(packed.model);
  }
  std::vector<Vec3d> centers;
  TriangleMesh mesh;  // stays empty for the convex primitives (sphere_graph_repair.h)
  if (g.kind == GeometrySpec::Kind::Mesh) {
    if (!(std::isfinite(g.mesh_scale) && g.mesh_scale > 0))
      throw InputError(f, "geometry.mesh_scale", "must be a positive number");
    mesh = loadMesh(g.mesh_path);
    for (auto& v : mesh.vertices) v = v * g.mesh_scale;
    requireClosedMesh(mesh, g.mesh_path, "geometry.mesh");
    centers = sampleMesh(mesh, LatticeSpec{g.spacing, g.jitter, g.seed});
  } else {
    centers = sampleGeometry(g, f);
  }
  if (centers.empty()) throw InputError(f, "geometry.spacing_m", "the body holds no lattice cell (spacing too large?)");
  if (centers.size() > 5000000) throw InputError(f, "geometry.spacing_m", "more than 5 million spheres");
  MetaballModel mb;
  mb.rest_centers = std::move(centers);
  mb.rest_radii.assign(mb.size(), kRadiusFactor * g.spacing);
  mb.masses.assign(mb.size(), scene.material.density_kg_m3 * g.spacing * g.spacing * g.spacing);
  linkOverlapping(mb);
  // Cells of a thin part that meet the rest only at a corner (or not at all, with jitter) overlap nothing: link them
  // across gaps of up to one spacing inside the body, or drop them, so that no sphere is left without a constraint.
  const SphereGraphRepair repair = connectSphereGraph(mb, mesh, kStragglerReach * g.spacing);
  refuseLargeDrops(repair.dropped, int(mb.size()) + repair.dropped, f, "geometry.spacing_m", "lower it");
  if (fill_note) *fill_note = "lattice: " + describeSphereGraphRepair(repair, mb.size());
  return mb;
}

std::unique_ptr<SimulationModel> makeMetaballSimulation(const CompiledScene& scene, BackendKind backend,
                                                        Precision precision) {
  if (precision == Precision::Float64) return std::make_unique<MetaballSimulation<double>>(scene, backend);
  return std::make_unique<MetaballSimulation<float>>(scene, backend);
}

}  // namespace inc
