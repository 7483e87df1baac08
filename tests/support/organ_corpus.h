// The bring-your-own-organ corpus: meshes a user might bring (the shared public organs and shapes made here), the
// scene a user would write for each (mesh, material, a fixed base, every other key at its default) with a grasp, a
// straight cut or a curved cut, a run of it through the runner, and the checks issue 31 asks of that run.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/app/runner.h"
#include "host/assembly/metaball_model.h"
#include "host/assembly/organ_shapes.h"
#include "host/io/mesh.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "host/sim/metaball_simulation.h"
#include "host/sim/model_factory.h"
#include "tests/support/repo_paths.h"
#include "tests/support/shipped_scene_run.h"
#include "tests/support/temp_dir.h"

namespace inc::test {

// One mesh of the corpus: a shared file (skipped when absent) or a shape made here, written in file units.
struct CorpusMesh {
  const char* name;
  const char* shared_file;  // under ../shared/organs, or null for a made shape
  TriangleMesh (*make)();   // the made shape, in file units (null for a shared file)
  double largest_extent_m;  // mesh_scale brings the largest extent to this
};

enum class CorpusAction { Grasp, StraightCut, CurvedCut };

inline const char* actionName(CorpusAction a) {
  return a == CorpusAction::Grasp ? "grasp" : a == CorpusAction::StraightCut ? "straight_cut" : "curved_cut";
}

namespace corpus {

// A bent ellipsoid in millimetres (120 x 40 x 30 mm, bent along an 80 mm arc): issue 31's own first report.
inline TriangleMesh bentEllipsoidMm() {
  TriangleMesh m = makeSphereMesh(1.0, 12);
  const double R = 80.0;
  for (Vec3d& v : m.vertices) {
    const double x = 60.0 * v.x, y = 20.0 * v.y, z = 15.0 * v.z;
    const double th = x / R;  // |z| < R keeps the bend injective
    v = Vec3d((R + z) * std::sin(th), y, (R + z) * std::cos(th) - R);
  }
  return m;
}

// Two bulbs joined by a thin neck (radius a fifth of the bulbs'): a thin limb between two bodies, in metres.
inline TriangleMesh dumbbell() {
  TriangleMesh m = makeSphereMesh(1.0, 14);
  for (Vec3d& v : m.vertices) {
    const double a = std::fabs(v.x);
    const double w = 0.2 + 0.8 * std::min(1.0, (a / 0.6) * (a / 0.6));  // > 0: the map stays injective
    v = Vec3d(0.07 * v.x, 0.025 * w * v.y, 0.025 * w * v.z);
  }
  return m;
}

// A flat sheet, 10 x 10 cm and 6 mm thick, in metres.
inline TriangleMesh sheet() { return makeBoxMesh(Vec3d(0.05, 0.05, 0.003), 12); }

// A torus made here (genus 1), in metres.
inline TriangleMesh torus() { return makeTorusMesh(0.05, 0.018, 48, 16); }

// The liver-like shape 50 m from the origin (a VR room's coordinates): float32 positions lose 4 digits there.
inline TriangleMesh farLiver() {
  LiverLikeOptions o;
  o.target_vertices = 3000;
  o.width_m = 0.18;
  TriangleMesh m = makeLiverLikeMesh(o);
  for (Vec3d& v : m.vertices) v = v + Vec3d(50.0, -30.0, 20.0);
  return m;
}

}  // namespace corpus

inline const std::vector<CorpusMesh>& corpusMeshes() {
  static const std::vector<CorpusMesh> meshes = {
      {"liver_smooth", "liver-smooth.obj", nullptr, 0.15},
      {"liver2", "liver2.obj", nullptr, 0.15},
      {"liver_coarse", "liver.obj", nullptr, 0.15},
      {"bunny", "Bunny.stl", nullptr, 0.10},
      {"armadillo", "Armadillo_verysimplified.obj", nullptr, 0.15},
      {"torus_shared", "torus.obj", nullptr, 0.12},
      {"bent_ellipsoid_mm", nullptr, corpus::bentEllipsoidMm, 0.12},
      {"dumbbell", nullptr, corpus::dumbbell, 0.14},
      {"sheet", nullptr, corpus::sheet, 0.10},
      {"torus_made", nullptr, corpus::torus, 0.136},
      {"liver_far_from_origin", nullptr, corpus::farLiver, 0.18},
  };
  return meshes;
}

// What a corpus run did and measured.
struct CorpusResult {
  bool skipped = false;
  std::string skip_reason;
  ShippedSceneRecord rec;
  std::size_t spheres = 0;
  double spacing_m = 0;
  double rest_volume_m3 = 0;
  double final_volume_m3 = 0;  // signed, all pieces
  int pieces = 0;              // of kDebrisVertices vertices or more
  int fragments = 0;           // smaller pieces
  int open_edges = 0;          // boundary + non-manifold edges of the final surface (0: every piece closed)
  int inverted_pieces = 0;     // pieces of negative signed volume (an inside-out skin)
  int mesh_components = 0;     // connected pieces of the input mesh
  double ms_per_frame = 0;
};

namespace detail {

// Signed volume and vertex count of each connected piece of a surface.
inline void pieceVolumes(const TriangleMesh& m, std::vector<double>& volume, std::vector<int>& vertices) {
  std::vector<int> parent(m.vertices.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = int(i);
  auto find = [&](int a) {
    while (parent[std::size_t(a)] != a) a = parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];
    return a;
  };
  for (const auto& t : m.triangles)
    for (int c = 1; c < 3; ++c) parent[std::size_t(find(t[c]))] = find(t[0]);
  std::vector<int> id(m.vertices.size(), -1), used(m.vertices.size(), 0);
  for (const auto& t : m.triangles)
    for (int c = 0; c < 3; ++c) used[std::size_t(t[c])] = 1;
  volume.clear();
  vertices.clear();
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    if (!used[v]) continue;
    const int r = find(int(v));
    if (id[std::size_t(r)] < 0) {
      id[std::size_t(r)] = int(volume.size());
      volume.push_back(0.0);
      vertices.push_back(0);
    }
    ++vertices[std::size_t(id[std::size_t(r)])];
  }
  // About the first vertex, for accuracy far from the origin.
  const Vec3d o = m.vertices.empty() ? Vec3d() : m.vertices.front();
  for (const auto& t : m.triangles) {
    const Vec3d a = m.vertices[std::size_t(t[0])] - o, b = m.vertices[std::size_t(t[1])] - o,
                c = m.vertices[std::size_t(t[2])] - o;
    volume[std::size_t(id[std::size_t(find(t[0]))])] += dot(a, cross(b, c)) / 6.0;
  }
}

}  // namespace detail

// The scene a user would write for `mesh_file` (bounding box lo..hi in metres after `scale`): the mesh, a liver-like
// material, the base slab (lowest 15 % of the height) fixed, every other key at its default, and the action's tool.
inline nlohmann::json corpusScene(const std::string& mesh_file, double scale, const Vec3d& lo, const Vec3d& hi,
                                  CorpusAction action) {
  using nlohmann::json;
  const Vec3d ext = hi - lo, c = (lo + hi) * 0.5;
  json s;
  s["name"] = std::string("corpus_") + actionName(action);
  s["duration_s"] = 0.8;
  s["geometry"] = {{"kind", "mesh"}, {"mesh", mesh_file}, {"mesh_scale", scale}};
  // Liver: E about 5 kPa at small strain, nu 0.45 (nearly incompressible), 1060 kg/m^3 (docs/bring-your-own-organ.md).
  s["material"] = {{"youngs_modulus_pa", 5.0e3}, {"poisson_ratio", 0.45}, {"density_kg_m3", 1060}};
  s["models"] = {{"pbd_metaballs", true}};
  const double slab = lo.z + 0.15 * ext.z;
  const double pad = 0.05 * std::max({ext.x, ext.y, ext.z});
  s["fixed"] =
      json::array({{{"min_m", {lo.x - pad, lo.y - pad, lo.z - pad}}, {"max_m", {hi.x + pad, hi.y + pad, slab}}}});
  auto key = [](double t, const Vec3d& p, const Vec3d& d) {
    return json{{"t_s", t}, {"position_m", {p.x, p.y, p.z}}, {"direction", {d.x, d.y, d.z}}};
  };
  const Vec3d up(0, 0, 1);
  if (action == CorpusAction::Grasp) {
    // Close on the top near the middle at 0.1 s, lift by a fifth of the height by 0.6 s, hold.
    const Vec3d top(c.x, c.y, hi.z - 0.1 * ext.z);
    s["tools"] = json::array(
        {{{"name", "grasper"},
          {"kind", "grasper"},
          {"radius_m", 0.004},
          {"path",
           {key(0.1, top, -up), key(0.6, top + up * (0.2 * ext.z), -up), key(0.8, top + up * (0.2 * ext.z), -up)}}}});
    return s;
  }
  s["models"]["cutting"] = true;
  // A vertical blade centred on the body's mid height and three heights long: it reaches through the whole body,
  // also where it sags below its rest box.
  const double length = 3.0 * ext.z;
  std::vector<json> path;
  const double y0 = lo.y - pad, y1 = hi.y + pad;
  if (action == CorpusAction::StraightCut) {
    // Across y at 70 % of the width in x: a lobe comes off.
    const double x = lo.x + 0.7 * ext.x;
    path = {key(0.1, Vec3d(x, y0, c.z), up), key(0.5, Vec3d(x, y1, c.z), up)};
  } else {
    // An arc bulging towards -x across y, from and to 75 % of the width (an arc like liver_cut's).
    const int n = 8;
    for (int k = 0; k <= n; ++k) {
      const double u = double(k) / n;  // 0..1 along y
      const double y = y0 + u * (y1 - y0);
      const double x = lo.x + ext.x * (0.75 - 0.25 * std::sin(3.14159265358979 * u));
      path.push_back(key(0.1 + 0.4 * u, Vec3d(x, y, c.z), up));
    }
  }
  s["tools"] = json::array(
      {{{"name", "scalpel"}, {"kind", "scalpel"}, {"radius_m", 0.001}, {"length_m", length}, {"path", path}}});
  return s;
}

// Runs the corpus case on `backend`: writes the mesh when it is made here, builds the user's scene, runs it through
// the runner and its guard, and measures the final surface.
inline CorpusResult runCorpusCase(const CorpusMesh& cm, CorpusAction action, BackendKind backend) {
  CorpusResult res;
  const TempDir dir(std::string("corpus_") + cm.name);
  std::string mesh_file;
  if (cm.shared_file) {
    mesh_file = sharedPath(std::string("organs/") + cm.shared_file);
    if (!std::filesystem::exists(mesh_file)) {
      res.skipped = true;
      res.skip_reason = mesh_file + " is absent (the shared organ meshes are not committed)";
      return res;
    }
  } else {
    mesh_file = dir.file(std::string(cm.name) + ".obj");
    writeObj(mesh_file, cm.make());
  }
  TriangleMesh mesh = loadMesh(mesh_file);
  requireClosedMesh(mesh, mesh_file, "geometry.mesh");
  const MeshReport rep = analyzeMesh(mesh);
  const Vec3d ext = rep.bbox_max - rep.bbox_min;
  const double scale = cm.largest_extent_m / std::max({ext.x, ext.y, ext.z});
  res.mesh_components = rep.components;
  res.rest_volume_m3 = rep.signed_volume * scale * scale * scale;
  const nlohmann::json j = corpusScene(mesh_file, scale, rep.bbox_min * scale, rep.bbox_max * scale, action);
  const std::string scene_path = dir.file("scene.json");
  {
    std::FILE* f = std::fopen(scene_path.c_str(), "w");
    const std::string text = j.dump(1);
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
  }
  Scene scene = loadSceneFile(scene_path);
  scene.output.particles_ply = scene.output.mesh_obj = scene.output.vtk = false;
  const CompiledScene compiled = compileScene(scene);
  res.spacing_m = compiled.geometry.spacing;
  const MetaballModel spheres = buildSceneMetaballs(compiled);
  res.spheres = spheres.size();
  res.rec.sphere_graph_components = sphereGraphComponents(spheres);
  RunOptions opt;
  opt.backend = backend;
  opt.quiet = true;
  opt.out_dir = dir.file("out");
  ShippedSceneRecord& rec = res.rec;
  auto factory = [&rec](const CompiledScene& c, BackendKind kind) {
    std::vector<std::unique_ptr<SimulationModel>> models = createSceneModels(c, kind);
    if (!models.empty()) models[0] = std::make_unique<detail::RecordingModel>(std::move(models[0]), rec);
    return models;
  };
  rec.summary = runScene(scene, opt, factory);
  res.ms_per_frame = rec.summary.frames_done > 0 ? 1e3 * rec.summary.wall_s / double(rec.summary.frames_done) : 0;
  if (rec.has_surface) {
    std::vector<double> vol;
    std::vector<int> nv;
    detail::pieceVolumes(rec.surface, vol, nv);
    for (std::size_t p = 0; p < vol.size(); ++p) {
      res.final_volume_m3 += vol[p];
      if (nv[p] >= kDebrisVertices) {
        ++res.pieces;
        if (vol[p] < 0) ++res.inverted_pieces;
      } else {
        ++res.fragments;
      }
    }
    const MeshReport fr = analyzeMesh(rec.surface);
    res.open_edges = fr.boundary_edges + fr.non_manifold_edges;
  }
  return res;
}

// One table row: mesh, action, spheres, spacing, ms per frame, pieces (+fragments), volume change, result.
inline std::string corpusRow(const CorpusMesh& cm, CorpusAction a, const CorpusResult& r, const std::string& verdict) {
  char b[400];
  std::snprintf(b, sizeof b, "| %s | %s | %zu | %.1f | %.1f | %d (+%d) | %+.1f %% | %s |", cm.name, actionName(a),
                r.spheres, r.spacing_m * 1e3, r.ms_per_frame, r.pieces, r.fragments,
                r.rest_volume_m3 > 0 ? 100.0 * (r.final_volume_m3 / r.rest_volume_m3 - 1.0) : 0.0, verdict.c_str());
  return b;
}

// Issue 31's checks of a corpus run, one sentence per failure: it ends without a guard failure; the sphere graph has
// one component per mesh piece; the surface stays closed and none of its pieces inside out; its volume stays within
// `volume_tolerance` of the rest volume; a cut leaves at least two pieces, a grasp one.
inline std::vector<std::string> corpusFailures(const CorpusResult& r, CorpusAction a, double volume_tolerance) {
  std::vector<std::string> f;
  const RunSummary& s = r.rec.summary;
  if (s.failed) f.push_back("the guard stopped the run: " + s.failure);
  if (s.frames_done != s.frames_requested)
    f.push_back("ran " + std::to_string(s.frames_done) + " of " + std::to_string(s.frames_requested) + " frames");
  if (r.rec.sphere_graph_components != r.mesh_components)
    f.push_back("the sphere graph has " + std::to_string(r.rec.sphere_graph_components) + " groups for " +
                std::to_string(r.mesh_components) + " mesh piece(s) (stray spheres)");
  if (!r.rec.has_surface) {
    f.push_back("no surface");
    return f;
  }
  if (r.open_edges > 0) f.push_back(std::to_string(r.open_edges) + " open or non-manifold surface edges");
  if (r.inverted_pieces > 0) f.push_back(std::to_string(r.inverted_pieces) + " surface piece(s) inside out");
  const double change = r.final_volume_m3 / r.rest_volume_m3 - 1.0;
  if (!(std::fabs(change) <= volume_tolerance))
    f.push_back("surface volume changed by " + std::to_string(100.0 * change) + " %");
  if (a == CorpusAction::Grasp && r.pieces != 1) f.push_back(std::to_string(r.pieces) + " pieces after a grasp");
  if (a != CorpusAction::Grasp && r.pieces < 2) f.push_back(std::to_string(r.pieces) + " piece(s) after a cut");
  return f;
}

}  // namespace inc::test
