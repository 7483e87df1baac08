// The BEM organ of a scene: loading and checking its mesh, its supports from the fixed regions, its scene keys.
#include "host/scene/global_organ_mesh.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "model/input_error.h"

namespace inc {

TriangleMesh loadGlobalOrganMesh(const std::string& path, double scale) {
  if (!(scale > 0.0) || !std::isfinite(scale)) throw InputError(path, "", "the mesh scale must be finite and > 0");
  TriangleMesh mesh = loadMesh(path);
  requireClosedMesh(mesh, path, "");
  const int E = int(mesh.triangles.size());
  if (E > kMaxBemElements)
    throw InputError(path, "", std::to_string(E) + " triangles, more than the " + std::to_string(kMaxBemElements) +
                                   " a dense BEM model can precompute here (its matrices grow as the square and its "
                                   "inverse as the cube of that); use a coarse organ mesh");
  for (Vec3d& v : mesh.vertices) v = v * scale;
  for (int j = 0; j < E; ++j) {
    const auto& t = mesh.triangles[std::size_t(j)];
    const Vec3d a = mesh.vertices[std::size_t(t[0])], b = mesh.vertices[std::size_t(t[1])],
                c = mesh.vertices[std::size_t(t[2])];
    const double longest = std::max({norm(b - a), norm(c - b), norm(a - c)});
    if (!(norm(cross(b - a, c - a)) > 1e-10 * longest * longest))
      throw InputError(path, "triangle " + std::to_string(j), "is degenerate (zero area): a boundary element needs an area");
  }
  return mesh;
}

std::vector<BemBc> organSupports(const TriangleMesh& mesh, const std::vector<FixedRegion>& fixed) {
  Vec3d lo = mesh.vertices.empty() ? Vec3d() : mesh.vertices[0], hi = lo;
  for (const Vec3d& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], v[a]);
      hi[a] = std::max(hi[a], v[a]);
    }
  const double tol = 1e-9 * norm(hi - lo);  // a flat box at a face's height holds that face's centroids
  std::vector<BemBc> bc(mesh.triangles.size(), BemBc::kTraction);
  for (std::size_t j = 0; j < mesh.triangles.size(); ++j) {
    const auto& t = mesh.triangles[j];
    const Vec3d c = (mesh.vertices[std::size_t(t[0])] + mesh.vertices[std::size_t(t[1])] + mesh.vertices[std::size_t(t[2])]) *
                    (1.0 / 3.0);
    for (const FixedRegion& f : fixed) {
      bool inside = true;
      for (int a = 0; a < 3; ++a) inside = inside && c[a] >= f.min[a] - tol && c[a] <= f.max[a] + tol;
      if (inside) bc[j] = BemBc::kDisplacement;
    }
  }
  return bc;
}

void readGlobalModelKeys(const scene_json::ObjectReader& r, const std::string& base_dir,
                         const std::vector<FixedRegion>& fixed, HapticsSpec& h) {
  if (h.global_model != "bem") {
    for (const char* k : {"global_mesh", "global_mesh_scale", "global_cache"})
      if (r.has(k)) r.fail(k, "is used only with global_model \"bem\"");
    return;
  }
  if (!r.has("global_mesh")) r.fail("global_mesh", "is required with global_model \"bem\" (the organ's closed surface mesh)");
  const std::string rel = r.string("global_mesh", "");
  if (rel.empty()) r.fail("global_mesh", "must name a mesh file");
  h.global_mesh = scene_json::resolvePath(rel, base_dir);
  TriangleMesh mesh;
  try {
    mesh = loadGlobalOrganMesh(h.global_mesh, h.global_mesh_scale);
  } catch (const InputError& e) {
    r.fail("global_mesh", e.what());
  }
  const std::vector<BemBc> bc = organSupports(mesh, fixed);
  if (std::find(bc.begin(), bc.end(), BemBc::kDisplacement) == bc.end())
    r.fail("global_mesh", h.global_mesh + ": no element centroid lies in a fixed region: the BEM global model needs the "
                          "organ held somewhere (a `fixed` box around part of its surface)");
  if (r.has("global_cache")) {
    const std::string c = r.string("global_cache", "");
    if (c.empty()) r.fail("global_cache", "must name a file (the precompute is always cached)");
    h.global_cache = scene_json::resolvePath(c, base_dir);
  } else if (!r.file().empty() && r.file()[0] != '<') {
    h.global_cache = scene_json::resolvePath(std::filesystem::path(r.file()).stem().string() + ".bemcache", base_dir);
  } else {
    h.global_cache = h.global_mesh + ".bemcache";
  }
}

}  // namespace inc
