// The BEM organ: loading and checking its closed surface mesh, and its supports from the fixed regions.
#include "host/compiled/bem_organ_mesh.h"

#include <algorithm>
#include <cmath>

#include "host/io/mesh_self_intersection.h"
#include "model/input_error.h"

namespace inc {

TriangleMesh loadGlobalOrganMesh(const std::string& path, double scale) {
  if (!(scale > 0.0) || !std::isfinite(scale)) throw InputError(path, "", "the mesh scale must be finite and > 0");
  TriangleMesh mesh = loadMesh(path);
  requireClosedMesh(mesh, path, "");
  requireFewSelfIntersections(mesh, path, "");  // a boundary integral over a folded surface counts it twice
  const int E = int(mesh.triangles.size());
  if (E > kMaxBemElements)
    throw InputError(path, "",
                     std::to_string(E) + " triangles, more than the " + std::to_string(kMaxBemElements) +
                         " a dense BEM model can precompute here (its matrices grow as the square and its "
                         "inverse as the cube of that); use a coarse organ mesh");
  for (Vec3d& v : mesh.vertices) v = v * scale;
  for (int j = 0; j < E; ++j) {
    const auto& t = mesh.triangles[std::size_t(j)];
    const Vec3d a = mesh.vertices[std::size_t(t[0])], b = mesh.vertices[std::size_t(t[1])],
                c = mesh.vertices[std::size_t(t[2])];
    const double longest = std::max({norm(b - a), norm(c - b), norm(a - c)});
    if (!(norm(cross(b - a, c - a)) > 1e-10 * longest * longest))
      throw InputError(path, "triangle " + std::to_string(j),
                       "is degenerate (zero area): a boundary element needs an area");
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
    const Vec3d c =
        (mesh.vertices[std::size_t(t[0])] + mesh.vertices[std::size_t(t[1])] + mesh.vertices[std::size_t(t[2])]) *
        (1.0 / 3.0);
    for (const FixedRegion& f : fixed) {
      bool inside = true;
      for (int a = 0; a < 3; ++a) inside = inside && c[a] >= f.min[a] - tol && c[a] <= f.max[a] + tol;
      if (inside) bc[j] = BemBc::kDisplacement;
    }
  }
  return bc;
}

}  // namespace inc
