// Runs a shipped scene through the runner (`incision run`) on a backend and checks it against its bounds row.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "host/app/runner.h"
#include "host/io/mesh.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "host/sim/metaball_simulation.h"
#include "host/sim/model_factory.h"
#include "tests/support/repo_paths.h"
#include "tests/support/shipped_scene_table.h"
#include "tests/support/temp_dir.h"

namespace inc::test {

// What a run did, frame by frame and at its end (the first model's; every shipped scene has one).
struct ShippedSceneRecord {
  RunSummary summary;
  long frames = 0;
  bool all_finite = true;
  double energy_max_j = 0.0;  // largest kinetic + elastic energy over the frames
  std::map<std::string, double> counter_last, counter_max, counter_sum;
  bool final_positions_finite = true;
  bool has_surface = false;
  TriangleMesh surface;              // the final surface (empty without one)
  int sphere_graph_components = -1;  // of the scene's sphere set before the run (-1: not a sphere model)
};

namespace detail {

// Passes every call through to the scene's model and keeps what each frame reported and, when the runner lets go of
// it, the final positions and surface.
class RecordingModel final : public SimulationModel {
 public:
  RecordingModel(std::unique_ptr<SimulationModel> model, ShippedSceneRecord& record)
      : model_(std::move(model)), rec_(record) {}
  ~RecordingModel() override {
    std::vector<Vec3d> x;
    model_->currentPositions(x);
    for (const Vec3d& p : x) rec_.final_positions_finite = rec_.final_positions_finite && isFinite(p);
    rec_.has_surface = model_->currentSurface(rec_.surface);
  }

  FrameReport advance(double frame_dt) override {
    FrameReport r = model_->advance(frame_dt);
    ++rec_.frames;
    rec_.all_finite = rec_.all_finite && r.finite;
    rec_.energy_max_j = std::max(rec_.energy_max_j, r.kinetic_energy + r.elastic_energy);
    for (const auto& [name, value] : r.counters) {
      rec_.counter_last[name] = value;
      rec_.counter_max[name] = rec_.counter_max.count(name) ? std::max(rec_.counter_max[name], value) : value;
      rec_.counter_sum[name] += value;
    }
    return r;
  }
  std::string name() const override { return model_->name(); }
  BackendKind backend() const override { return model_->backend(); }
  std::size_t particleCount() const override { return model_->particleCount(); }
  void saveCheckpoint() override { model_->saveCheckpoint(); }
  void restoreCheckpoint() override { model_->restoreCheckpoint(); }
  void scaleTimeStep(double factor) override { model_->scaleTimeStep(factor); }
  void currentPositions(std::vector<Vec3d>& out) const override { model_->currentPositions(out); }
  bool currentSurface(TriangleMesh& out) const override { return model_->currentSurface(out); }
  MemoryReport memory() const override { return model_->memory(); }
  ToolSupport toolSupport() const override { return model_->toolSupport(); }
  ToolResult applyTool(const ToolEvent& event) override { return model_->applyTool(event); }
  void cutWallTriangles(std::vector<std::uint8_t>& out) const override { model_->cutWallTriangles(out); }
  void renderLayers(RenderLayers& out) const override { model_->renderLayers(out); }

 private:
  std::unique_ptr<SimulationModel> model_;
  ShippedSceneRecord& rec_;
};

// Vertex counts of the surface's connected pieces (over shared vertices, as analyzeMesh counts them), largest first,
// and the vertices no triangle uses.
inline std::vector<int> surfacePieceSizes(const TriangleMesh& m, int& unused_vertices) {
  std::vector<int> parent(m.vertices.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = int(i);
  auto find = [&](int a) {
    while (parent[std::size_t(a)] != a) a = parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];
    return a;
  };
  std::vector<char> used(m.vertices.size(), 0);
  for (const auto& t : m.triangles)
    for (int c = 0; c < 3; ++c) {
      used[std::size_t(t[c])] = 1;
      parent[std::size_t(find(t[c]))] = find(t[0]);
    }
  std::map<int, int> size;
  unused_vertices = 0;
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    if (used[v]) ++size[find(int(v))];
    unused_vertices += used[v] ? 0 : 1;
  }
  std::vector<int> out;
  for (const auto& [root, n] : size) out.push_back(n);
  std::sort(out.rbegin(), out.rend());
  return out;
}

inline double reduced(const ShippedSceneRecord& r, const CounterBound& c) {
  const auto& m = c.over == CounterBound::Over::Last  ? r.counter_last
                  : c.over == CounterBound::Over::Max ? r.counter_max
                                                      : r.counter_sum;
  const auto it = m.find(c.counter);
  return it == m.end() ? std::nan("") : it->second;
}

}  // namespace detail

// Runs scenes/<row.scene>.json for row.frames frames (0: its duration) on `backend` with the runner and its guard,
// outputs off (the record keeps the final surface).
inline ShippedSceneRecord runShippedScene(const ShippedSceneBounds& row, BackendKind backend) {
  Scene scene = loadSceneFile(sourcePath(std::string("scenes/") + row.scene + ".json"));
  scene.output.particles_ply = scene.output.mesh_obj = scene.output.vtk = false;
  scene.output.every_frames = 0;
  ShippedSceneRecord rec;
  const CompiledScene compiled = compileScene(scene);
  if (compiled.models.pbd_metaballs || compiled.models.cutting)
    rec.sphere_graph_components = sphereGraphComponents(buildSceneMetaballs(compiled));
  const TempDir out(std::string("shipped_") + row.scene);
  RunOptions opt;
  if (row.frames > 0) opt.frames = row.frames;
  opt.backend = backend;
  opt.quiet = true;
  opt.out_dir = out.str();
  auto factory = [&rec](const CompiledScene& c, BackendKind kind) {
    std::vector<std::unique_ptr<SimulationModel>> models = createSceneModels(c, kind);
    if (!models.empty()) models[0] = std::make_unique<detail::RecordingModel>(std::move(models[0]), rec);
    return models;
  };
  rec.summary = runScene(scene, opt, factory);
  return rec;
}

// Failures as one message, "; " between them ("" when none).
inline std::string joinedFailures(const std::vector<std::string>& failures) {
  std::string all;
  for (const std::string& f : failures) all += (all.empty() ? "" : "; ") + f;
  return all;
}

// Every bound of `row` the run broke, one sentence each (empty: it met them all).
inline std::vector<std::string> shippedSceneFailures(const ShippedSceneBounds& row, const ShippedSceneRecord& r) {
  std::vector<std::string> f;
  auto fail = [&f](const std::string& what) { f.push_back(what); };
  auto num = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", v);
    return std::string(b);
  };
  const RunSummary& s = r.summary;
  if (s.failed) fail("the guard stopped the run: " + s.failure);
  if (s.retries > 0) fail("the guard rolled back and retried " + std::to_string(s.retries) + " frame(s)");
  if (s.frames_done != s.frames_requested)
    fail("ran " + std::to_string(s.frames_done) + " of " + std::to_string(s.frames_requested) + " frames");
  if (!r.all_finite || !r.final_positions_finite) fail("a position became NaN or infinite");
  if (!(r.energy_max_j <= row.energy_max_j))
    fail("kinetic + elastic energy reached " + num(r.energy_max_j) + " J, bound " + num(row.energy_max_j) + " J");
  if (!(s.max_displacement >= row.displacement_min_m && s.max_displacement <= row.displacement_max_m))
    fail("largest displacement " + num(s.max_displacement) + " m, expected [" + num(row.displacement_min_m) + ", " +
         num(row.displacement_max_m) + "] m");
  if (r.sphere_graph_components != -1 && r.sphere_graph_components != 1)
    fail("the sphere graph has " + std::to_string(r.sphere_graph_components) +
         " connected groups before the run (stray spheres): expected 1");
  if (row.pieces_min >= 0) {
    if (!r.has_surface) {
      fail("the model has no surface to count pieces of");
    } else {
      int unused = 0;
      const std::vector<int> sizes = detail::surfacePieceSizes(r.surface, unused);
      const int n = int(std::count_if(sizes.begin(), sizes.end(), [](int v) { return v >= kDebrisVertices; }));
      const int debris = int(sizes.size()) - n;
      if (n < row.pieces_min || n > row.pieces_max)
        fail("the final surface has " + std::to_string(n) + " piece(s) of " + std::to_string(kDebrisVertices) +
             " vertices or more, expected [" + std::to_string(row.pieces_min) + ", " + std::to_string(row.pieces_max) +
             "]");
      if (debris > row.debris_max)
        fail("the final surface has " + std::to_string(debris) + " fragment(s) of under " +
             std::to_string(kDebrisVertices) + " vertices, expected at most " + std::to_string(row.debris_max));
      const double used = double(r.surface.vertices.size()) - unused;
      if (!sizes.empty() && double(sizes[0]) < row.largest_piece_min * used)
        fail("the largest piece holds " + num(sizes[0] / used) + " of the surface's vertices, expected at least " +
             num(row.largest_piece_min));
      if (unused > 0) fail(std::to_string(unused) + " surface vertices belong to no triangle (stray particles)");
    }
  }
  for (const CounterBound& c : row.counters) {
    const double v = detail::reduced(r, c);
    const char* over = c.over == CounterBound::Over::Last ? "last" : c.over == CounterBound::Over::Max ? "max" : "sum";
    if (!(v >= c.min && v <= c.max))
      fail(std::string("counter ") + c.counter + " (" + over + " over the frames) is " + num(v) + ", expected [" +
           num(c.min) + ", " + num(c.max) + "]");
  }
  return f;
}

// One line of what the run measured, for the test log (bounds are tuned and reviewed against these).
inline std::string shippedSceneMeasured(const ShippedSceneRecord& r) {
  std::ostringstream o;
  o << r.frames << " frames, " << r.summary.wall_s << " s wall; energy max " << r.energy_max_j
    << " J; largest displacement " << r.summary.max_displacement << " m";
  if (r.has_surface) {
    int unused = 0;
    const std::vector<int> pieces = detail::surfacePieceSizes(r.surface, unused);
    const long debris = std::count_if(pieces.begin(), pieces.end(), [](int v) { return v < kDebrisVertices; });
    o << "; surface pieces " << pieces.size() - std::size_t(debris) << " and " << debris << " fragment(s) (largest "
      << (pieces.empty() ? 0 : pieces[0]) << " of " << r.surface.vertices.size() << " vertices)";
  }
  if (r.sphere_graph_components >= 0) o << "; sphere groups at start " << r.sphere_graph_components;
  return o.str();
}

}  // namespace inc::test
