// Tearing sheet SimulationModel: scene -> sheet, frame loop with grasper pull and scalpel removal, energies and
// counters.
#include "host/sim/tearing_simulation.h"

#include <algorithm>
#include <cmath>

#include "host/tear/tearing_driver.h"
#include "model/frame_budget.h"
#include "model/input_error.h"

namespace inc {

namespace {

// The sheet's surface for output and drawing: its particles and triangles as they are now.
template <typename T>
TriangleMesh tearSurface(const TearSheet<T>& s) {
  TriangleMesh m;
  m.vertices.reserve(s.size());
  for (const auto& p : s.x) m.vertices.push_back(Vec3d(p));
  for (const auto& t : s.tris) m.triangles.push_back({t[0], t[1], t[2]});
  return m;
}

Vec3d toolPosition(const ToolSpec& t, double time) {
  if (t.path.empty()) return Vec3d();
  if (time <= t.path.front().t) return t.path.front().position;
  for (std::size_t k = 1; k < t.path.size(); ++k)
    if (time <= t.path[k].t) {
      const double a = (time - t.path[k - 1].t) / std::max(1e-12, t.path[k].t - t.path[k - 1].t);
      return t.path[k - 1].position + (t.path[k].position - t.path[k - 1].position) * a;
    }
  return t.path.back().position;
}

Vec3d toolDirection(const ToolSpec& t, double time) {
  if (t.path.empty()) return Vec3d(0, 0, -1);
  std::size_t k = 0;
  while (k + 1 < t.path.size() && t.path[k + 1].t <= time) ++k;
  const Vec3d d = t.path[k].direction;
  const double l = norm(d);
  return l > 0 ? d * (1.0 / l) : Vec3d(0, 0, -1);
}

}  // namespace

TearingSceneSetup tearingSetupFromScene(const CompiledScene& scene) {
  const std::string& f = scene.file;
  TearingSceneSetup s;
  const GeometrySpec& g = scene.geometry;
  const TearingSpec& ts = scene.tearing;
  const double k = ts.k_pa > 0 ? ts.k_pa : scene.material.youngs_modulus_pa;
  const double tau = ts.tau_f_pa > 0 ? ts.tau_f_pa : 0.1 * k;
  const double h = g.spacing;
  if (!(h > 0)) throw InputError(f, "geometry.spacing_m", "must be > 0");
  const double rho_a = scene.material.density_kg_m3 * h;
  if (g.kind == GeometrySpec::Kind::Box) {
    const int nx = int(std::floor(g.size.x / h + 1e-9)) + 1, ny = int(std::floor(g.size.y / h + 1e-9)) + 1;
    if (double(nx) * ny > 2.0e7) throw InputError(f, "geometry.spacing_m", "too many particles");
    s.sheet = makeTearGrid<double>(nx, ny, h, rho_a, g.center - Vec3d(0.5 * g.size.x, 0.5 * g.size.y, 0), k, tau);
  } else if (g.kind == GeometrySpec::Kind::Beam) {
    const double r = 0.5 * g.size.y, len = g.size.x;
    const int na = std::max(3, int(std::lround(6.283185307179586 * r / h))), nl = int(std::floor(len / h + 1e-9)) + 1;
    if (double(na) * nl > 2.0e7) throw InputError(f, "geometry.spacing_m", "too many particles");
    TearSheet<double> tube = makeTearTube<double>(na, nl, r, len, rho_a, k, tau);
    // The tube is built about z; lay it along x through the centre: (x, y, z) -> (z - len/2, x, y) + c.
    for (auto* arr : {&tube.rest, &tube.x})
      for (auto& p : *arr) p = Vec3d(p.z - 0.5 * len, p.x, p.y) + g.center;
    for (auto& n : tube.ref_normal) n = Vec3d(n.z, n.x, n.y);
    s.sheet = std::move(tube);
  } else if (g.kind == GeometrySpec::Kind::Mesh) {
    TriangleMesh m = loadMesh(g.mesh_path);
    if (m.triangles.empty()) throw InputError(g.mesh_path, "triangles", "the skin mesh has no triangles");
    TearSheet<double> t;
    for (const auto& v : m.vertices) t.rest.push_back(v * g.mesh_scale);
    const std::size_t n = t.rest.size();
    t.mass.assign(n, 0.0);
    for (std::size_t q = 0; q < m.triangles.size(); ++q) {
      const auto& tr = m.triangles[q];
      const Vec3d av = cross(t.rest[tr[1]] - t.rest[tr[0]], t.rest[tr[2]] - t.rest[tr[0]]) * 0.5;
      const double a = norm(av);
      if (!(a > 0) || tr[0] == tr[1] || tr[1] == tr[2] || tr[0] == tr[2])
        throw InputError(g.mesh_path, "face " + std::to_string(q), "degenerate triangle");
      t.tris.push_back({tr[0], tr[1], tr[2]});
      t.ref_normal.push_back(av * (1.0 / a));
      for (int c = 0; c < 3; ++c) t.mass[tr[c]] += rho_a * a / 3.0;
    }
    // Vertices no triangle uses carry no mass: removeTearParticles drops particles left without triangles.
    std::vector<std::uint8_t> none(n, 0);
    t.x = t.rest;
    t.v.assign(n, Vec3d());
    t.fixed.assign(n, 0);
    t.k.assign(n, k);
    t.tau_f.assign(n, tau);
    for (std::size_t i = 0; i < n; ++i)
      if (!(t.mass[i] > 0)) t.mass[i] = 1.0;  // keeps rebuildTopology valid; these unused vertices are dropped next
    t.rebuildTopology();
    removeTearParticles(t, none, false, TearParams<double>());
    s.sheet = std::move(t);
  } else {
    throw InputError(f, "geometry.kind", "the tearing model needs a box (sheet), beam (tube) or mesh (skin surface)");
  }
  std::vector<TearRegion> regions;
  for (const auto& r : ts.regions) {
    TearRegion q;
    q.min = r.min;
    q.max = r.max;
    q.k_pa = r.k_pa > 0 ? r.k_pa : k;
    q.tau_f_pa = r.tau_f_pa > 0 ? r.tau_f_pa : tau;
    regions.push_back(q);
  }
  applyTearRegions(s.sheet, regions);
  for (const auto& fr : scene.fixed) fixTearParticles(s.sheet, fr.min, fr.max);
  s.tear.criterion = parseTearCriterion(ts.criterion, f, "tearing.criterion");
  s.tear.seed = ts.seed;
  s.tear.break_strain =
      ts.break_strain;  // default 0.2: the traditional criterion at the default stress, k 0.2 = 2 tau_f
  s.tear.random_range = ts.random_range;
  s.model.stretch_compliance = scene.pbd.stretch_compliance;
  s.model.bending_compliance = 10.0;
  s.damping_per_s = scene.material.damping_per_s;
  s.iterations = scene.pbd.iterations;
  if (scene.pbd.chebyshev_rho >
      0)  // the tearing solve patches its model on the device, which the acceleration does not support
    throw InputError(f, "pbd.chebyshev_rho",
                     "not supported by the tearing model (its solve is patched as it tears): use 0");
  s.xpbd = scene.pbd.xpbd;
  s.solver = scene.pbd.solver;
  for (std::size_t t = 0; t < scene.tools.size(); ++t)
    if (scene.tools[t].kind != "grasper" && scene.tools[t].kind != "scalpel")
      throw InputError(f, "tools[" + std::to_string(t) + "].kind",
                       "the tearing model supports grasper and scalpel tools");
  return s;
}

namespace {

template <typename T>
class TearingSimulation final : public SimulationModel {
 public:
  TearingSimulation(const CompiledScene& scene, TearingSceneSetup setup, BackendKind backend)
      : scene_(scene),
        driver_(convert(setup.sheet), convertParams(setup.tear), setup.model, stepParams(scene, setup), backend) {
    grabTools();
    checkpoint_ = driver_.sheet();
    checkFixedSubstepsFit(scene.solver.substeps, driver_.particleCount(), scene.solver.max_substeps, scene.file);
  }

  std::string name() const override { return "tearing_sheet"; }
  BackendKind backend() const override { return driver_.kind(); }
  std::size_t particleCount() const override { return driver_.particleCount(); }

  FrameReport advance(double frame_dt) override {
    FrameReport r;
    // The frame budget (model/frame_budget.h): the guard's retries double the substeps; beyond the limit, refused.
    if (std::string why =
            pbdSubstepRefusal(driver_.stepParams().substeps, driver_.particleCount(), scene_.solver.max_substeps);
        !why.empty()) {
      refuseFrame(r, std::move(why));
      return r;
    }
    driver_.stepParams().frame_dt = T(frame_dt);
    const double t1 = time_ + frame_dt;
    int removed = scalpels(t1);
    std::vector<std::int32_t> ids;
    std::vector<Vec3<T>> to;
    for (const Grab& g : grabs_) {
      const Vec3d shift = toolPosition(scene_.tools[g.tool], t1) - toolPosition(scene_.tools[g.tool], 0.0);
      for (std::size_t k = 0; k < g.ids.size(); ++k) {
        ids.push_back(g.ids[k]);
        to.push_back(g.start[k] + Vec3<T>(shift));
      }
    }
    const TearFrameStats st = driver_.advance(ids, to);
    time_ = t1;
    r.substeps = driver_.stepParams().substeps;
    r.dt = frame_dt / r.substeps;
    r.stages = {{"solve", st.solve_ms}, {"tear", st.tear_ms}, {"rebuild", st.rebuild_ms}};
    const TearSheet<T>& s = driver_.sheet();
    const Vec3d g = scene_.solver.gravity;
    for (std::size_t i = 0; i < s.size(); ++i) {
      const Vec3d x(s.x[i]), v(s.v[i]), x0(s.rest[i]);
      r.kinetic_energy += 0.5 * double(s.mass[i]) * norm2(v);
      r.potential_energy -= double(s.mass[i]) * dot(g, x - x0);
      r.max_displacement = std::max(r.max_displacement, norm(x - x0));
      if (r.finite && !isFinite(x)) {
        r.finite = false;
        r.failure_stage = "solve";
        r.failure_particle = std::int64_t(i);
      }
    }
    if (driver_.stepParams().xpbd && setupCompliance_ > 0)
      for (std::size_t e = 0; e < s.edge_a.size(); ++e) {
        const double c =
            double(norm(s.x[s.edge_a[e]] - s.x[s.edge_b[e]]) - norm(s.rest[s.edge_a[e]] - s.rest[s.edge_b[e]]));
        r.elastic_energy += 0.5 * c * c / setupCompliance_;
      }
    r.counters["splits"] = st.splits;
    r.counters["yielding"] = st.yielding;
    r.counters["deferred"] = st.deferred;
    r.counters["removed"] = removed;
    r.counters["particles"] = double(s.size());
    r.counters["triangles"] = double(s.tris.size());
    return r;
  }

  void saveCheckpoint() override {
    checkpoint_ = driver_.sheet();
    checkpoint_time_ = time_;
    checkpoint_grabs_ = grabs_;
  }
  void restoreCheckpoint() override {
    driver_.mutableSheet() = checkpoint_;
    driver_.resetModel();
    time_ = checkpoint_time_;
    grabs_ = checkpoint_grabs_;
  }
  void scaleTimeStep(double factor) override {
    if (!(factor > 0)) return;
    auto& p = driver_.stepParams();
    p.substeps = std::max(1, int(std::ceil(p.substeps / factor)));
  }
  void currentPositions(std::vector<Vec3d>& out) const override {
    out.clear();
    for (const auto& p : driver_.sheet().x) out.push_back(Vec3d(p));
  }
  bool currentSurface(TriangleMesh& out) const override {
    out = tearSurface(driver_.sheet());
    return true;
  }
  MemoryReport memory() const override {
    MemoryReport m = driver_.memory();
    const auto& s = driver_.sheet();
    m.host_bytes += s.size() * (3 * sizeof(Vec3<T>) + 3 * sizeof(T) + 1) + s.tris.size() * (12 + sizeof(Vec3<T>));
    return m;
  }

  // The viewer's layers: the fixed particles and those the graspers hold. No forces: the graspers move their
  // particles kinematically (TearingDriver::advance), so no constraint force is defined for them.
  void renderLayers(RenderLayers& out) const override {
    out = RenderLayers{};
    const TearSheet<T>& s = driver_.sheet();
    for (std::size_t i = 0; i < s.size(); ++i)
      if (s.fixed[i]) {
        out.fixed_ids.push_back(std::int32_t(i));
        out.fixed_points.push_back(Vec3d(s.x[i]));
      }
    for (const Grab& g : grabs_)
      for (std::int32_t id : g.ids) {
        out.held_ids.push_back(id);
        out.held_points.push_back(Vec3d(s.x[std::size_t(id)]));
      }
  }

  double setupCompliance_ = 0.0;

 private:
  struct Grab {
    std::size_t tool = 0;
    std::vector<std::int32_t> ids;
    std::vector<Vec3<T>> start;
  };

  static TearSheet<T> convert(const TearSheet<double>& d) {
    TearSheet<T> s;
    for (const auto& p : d.rest) s.rest.push_back(Vec3<T>(p));
    for (const auto& p : d.x) s.x.push_back(Vec3<T>(p));
    for (const auto& p : d.v) s.v.push_back(Vec3<T>(p));
    for (double m : d.mass) s.mass.push_back(T(m));
    s.fixed = d.fixed;
    for (double k : d.k) s.k.push_back(T(k));
    for (double t : d.tau_f) s.tau_f.push_back(T(t));
    s.tris = d.tris;
    for (const auto& n : d.ref_normal) s.ref_normal.push_back(Vec3<T>(n));
    s.rebuildTopology();
    return s;
  }
  static TearParams<T> convertParams(const TearParams<double>& d) {
    TearParams<T> p;
    p.criterion = d.criterion;
    p.break_strain = T(d.break_strain);
    p.random_range = T(d.random_range);
    p.t_lo = T(d.t_lo);
    p.t_hi = T(d.t_hi);
    p.min_area_ratio = T(d.min_area_ratio);
    p.seed = d.seed;
    return p;
  }
  static PbdStepParams<T> stepParams(const CompiledScene& scene, const TearingSceneSetup& s) {
    PbdStepParams<T> p;
    p.frame_dt = T(scene.solver.frame_dt);
    p.substeps = scene.solver.substeps > 0 ? scene.solver.substeps : 4;
    p.iterations = s.iterations;
    p.xpbd = s.xpbd;
    p.solver = parsePbdSolver(s.solver, scene.file, "pbd.solver");
    p.gravity = Vec3<T>(scene.solver.gravity);
    p.damping = T(s.damping_per_s);
    p.volume_preservation = false;
    return p;
  }

  std::vector<std::uint8_t> markBlade(const ToolSpec& tool, double time) const {
    const Vec3d a = toolPosition(tool, time), b = a + toolDirection(tool, time) * tool.length;
    return markNearSegment(driver_.sheet(), a, b, tool.radius);
  }

  void grabTools() {
    for (std::size_t t = 0; t < scene_.tools.size(); ++t) {
      if (scene_.tools[t].kind != "grasper") continue;
      Grab g;
      g.tool = t;
      const auto mark = markBlade(scene_.tools[t], 0.0);
      for (std::size_t i = 0; i < mark.size(); ++i)
        if (mark[i] && !driver_.sheet().fixed[i]) {
          g.ids.push_back(std::int32_t(i));
          g.start.push_back(driver_.sheet().x[i]);
        }
      grabs_.push_back(std::move(g));
    }
  }

  int scalpels(double time) {
    int removed = 0;
    for (std::size_t t = 0; t < scene_.tools.size(); ++t) {
      if (scene_.tools[t].kind != "scalpel") continue;
      const ToolSpec& tool = scene_.tools[t];
      if (tool.path.empty() || time < tool.path.front().t || time > tool.path.back().t) continue;  // blade not in
      const auto mark = markBlade(scene_.tools[t], time);
      if (std::find(mark.begin(), mark.end(), std::uint8_t(1)) == mark.end()) continue;
      std::vector<std::int32_t> remap;
      removed +=
          driver_.removeParticles(mark, false, &remap);  // the blade deletes what it touches; tearing acts around it
      for (Grab& g : grabs_) {  // grabbed particles follow the renumbering; removed ones are let go
        std::vector<std::int32_t> ids;
        std::vector<Vec3<T>> start;
        for (std::size_t k = 0; k < g.ids.size(); ++k)
          if (remap[g.ids[k]] >= 0) {
            ids.push_back(remap[g.ids[k]]);
            start.push_back(g.start[k]);
          }
        g.ids = std::move(ids);
        g.start = std::move(start);
      }
    }
    return removed;
  }

  CompiledScene scene_;
  TearingDriver<T> driver_;
  std::vector<Grab> grabs_, checkpoint_grabs_;
  TearSheet<T> checkpoint_;
  double time_ = 0.0, checkpoint_time_ = 0.0;
};

}  // namespace

std::unique_ptr<SimulationModel> makeTearingSimulation(const CompiledScene& scene, BackendKind backend,
                                                       Precision precision) {
  if (!scene.models.tearing)
    throw InputError(scene.file, "models.tearing", "is false: the scene does not ask for tearing");
  TearingSceneSetup setup = tearingSetupFromScene(scene);
  const double compliance = setup.model.stretch_compliance;
  if (precision == Precision::Float64) {
    auto m = std::make_unique<TearingSimulation<double>>(scene, std::move(setup), backend);
    m->setupCompliance_ = compliance;
    return m;
  }
  auto m = std::make_unique<TearingSimulation<float>>(scene, std::move(setup), backend);
  m->setupCompliance_ = compliance;
  return m;
}

}  // namespace inc
