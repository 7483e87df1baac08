// Packer input validation and safe repairs: welding, edge topology, orientation, volume, self-intersection.
#include "host/assembly/metaball_pack_checks.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <tuple>

#include "host/io/mesh_self_intersection.h"
#include "host/io/triangle_bvh.h"
#include "model/input_error.h"

namespace inc {
namespace {

std::string edgeName(int a, int b) { return "edge (" + std::to_string(a) + ", " + std::to_string(b) + ")"; }

// What no repair can fix, checked before anything else reads the mesh: no geometry, non-finite coordinates,
// vertex indices out of range.
void checkIndicesAndCoordinates(const TriangleMesh& mesh, const std::string& file, const std::string& key) {
  if (mesh.vertices.empty() || mesh.triangles.empty())
    throw InputError(file, key, "empty mesh: a closed surface with at least 4 triangles is needed");
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    if (!isFinite(mesh.vertices[i]))
      throw InputError(file, key + ".vertex " + std::to_string(i), "non-finite coordinate");
  const int nv = int(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (mesh.triangles[t][std::size_t(k)] < 0 || mesh.triangles[t][std::size_t(k)] >= nv)
        throw InputError(file, key + ".face " + std::to_string(t),
                         "vertex index " + std::to_string(mesh.triangles[t][std::size_t(k)]) + " out of range [0, " +
                             std::to_string(nv) + ")");
}

// Repair 1: weld bit-identical duplicates (STL-style meshes repeat every vertex per face); the triangles are
// re-indexed, the vertex list is kept. Repair 2: drop triangles whose corners repeat an index (zero area, no
// orientation).
void weldDuplicatesAndDropDegenerate(TriangleMesh& mesh, PackInputReport& rep) {
  const int nv = int(mesh.vertices.size());
  std::map<std::tuple<double, double, double>, int> first;
  std::vector<int> remap(static_cast<std::size_t>(nv));
  for (int i = 0; i < nv; ++i) {
    const Vec3d& p = mesh.vertices[std::size_t(i)];
    auto [it, inserted] = first.emplace(std::make_tuple(p.x + 0.0, p.y + 0.0, p.z + 0.0), i);  // +0.0: -0 == 0
    remap[std::size_t(i)] = it->second;
    if (!inserted) ++rep.welded_vertices;
  }
  std::vector<std::array<int, 3>> kept;
  kept.reserve(mesh.triangles.size());
  for (auto tri : mesh.triangles) {
    for (auto& v : tri) v = remap[std::size_t(v)];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) {
      ++rep.removed_triangles;
      continue;
    }
    kept.push_back(tri);
  }
  mesh.triangles.swap(kept);
}

// Edge topology: every undirected edge must have exactly two triangles traversing it in opposite directions.
void checkEdgeTopology(const TriangleMesh& mesh, const std::string& file, const std::string& key) {
  struct DirectedEdge {
    int lo, hi, forward, tri;
  };
  std::vector<DirectedEdge> edges;
  edges.reserve(mesh.triangles.size() * 3);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.triangles[t][std::size_t(k)], b = mesh.triangles[t][std::size_t((k + 1) % 3)];
      edges.push_back({std::min(a, b), std::max(a, b), a < b ? 1 : 0, int(t)});
    }
  std::sort(edges.begin(), edges.end(), [](const DirectedEdge& x, const DirectedEdge& y) {
    return std::tie(x.lo, x.hi, x.tri) < std::tie(y.lo, y.hi, y.tri);
  });
  int open = 0, nonmanifold = 0, inconsistent = 0;
  std::string first_open, first_nonmanifold, first_inconsistent;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    const std::size_t count = j - i;
    if (count == 1) {
      if (!open++) first_open = edgeName(edges[i].lo, edges[i].hi) + " of face " + std::to_string(edges[i].tri);
    } else if (count > 2) {
      if (!nonmanifold++)
        first_nonmanifold = edgeName(edges[i].lo, edges[i].hi) + " shared by " + std::to_string(count) + " faces";
    } else if (edges[i].forward == edges[i + 1].forward) {
      if (!inconsistent++)
        first_inconsistent = edgeName(edges[i].lo, edges[i].hi) + " traversed the same way by faces " +
                             std::to_string(edges[i].tri) + " and " + std::to_string(edges[i + 1].tri);
    }
    i = j;
  }
  if (open)
    throw InputError(file, key,
                     "open surface: " + std::to_string(open) + " boundary edge(s), first " + first_open +
                         "; the packer needs a closed surface (not repaired: filling holes would invent "
                         "geometry)");
  if (nonmanifold)
    throw InputError(file, key,
                     "non-manifold surface: " + std::to_string(nonmanifold) +
                         " edge(s) with more than "
                         "two faces, first " +
                         first_nonmanifold);
  if (inconsistent)
    throw InputError(
        file, key,
        "inconsistent orientation: " + std::to_string(inconsistent) + " edge(s), first " + first_inconsistent);
}

// Volume by the divergence theorem; an inward-oriented surface is flipped (safe: orientation is consistent).
// Also counts the zero-area triangles.
void orientOutwardAndMeasure(TriangleMesh& mesh, const std::string& file, const std::string& key,
                             PackInputReport& rep) {
  double six_v = 0.0;
  pack::Aabb box;
  for (const auto& p : mesh.vertices) box.grow(p);
  const Vec3d mid = (box.lo + box.hi) * 0.5;  // about the box centre, for accuracy
  for (const auto& t : mesh.triangles) {
    const Vec3d a = mesh.vertices[std::size_t(t[0])] - mid, b = mesh.vertices[std::size_t(t[1])] - mid,
                c = mesh.vertices[std::size_t(t[2])] - mid;
    six_v += dot(a, cross(b, c));
  }
  double volume = six_v / 6.0;
  const Vec3d e = box.extent();
  const double scale3 = std::pow(norm(e), 3.0);
  if (!(std::fabs(volume) > 1e-9 * scale3))
    throw InputError(
        file, key,
        "zero volume: the closed surface encloses " + std::to_string(volume) + " (flat or doubled-over surface)");
  if (volume < 0.0) {
    for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
    volume = -volume;
    rep.flipped = true;
  }
  rep.volume = volume;
  for (const auto& t : mesh.triangles) {
    const Vec3d n = cross(mesh.vertices[std::size_t(t[1])] - mesh.vertices[std::size_t(t[0])],
                          mesh.vertices[std::size_t(t[2])] - mesh.vertices[std::size_t(t[0])]);
    if (norm(n) <= 1e-14 * norm2(e)) ++rep.zero_area_triangles;
  }
}

// One line listing the repairs made or tolerated, "" when none.
std::string describeRepairs(const PackInputReport& rep) {
  std::ostringstream r;
  const char* sep = "";
  if (rep.welded_vertices) {
    r << sep << "welded " << rep.welded_vertices << " duplicate vertices";
    sep = "; ";
  }
  if (rep.removed_triangles) {
    r << sep << "dropped " << rep.removed_triangles << " degenerate triangles";
    sep = "; ";
  }
  if (rep.flipped) {
    r << sep << "flipped inward-oriented surface";
    sep = "; ";
  }
  if (rep.self_intersecting_faces) {
    r << sep << "tolerated " << rep.self_intersecting_faces << " locally self-intersecting faces";
    sep = "; ";
  }
  return r.str();
}

}  // namespace

PackInputReport preparePackInput(TriangleMesh& mesh, const std::string& file, const std::string& key,
                                 double max_self_intersecting_fraction) {
  PackInputReport rep;
  checkIndicesAndCoordinates(mesh, file, key);
  weldDuplicatesAndDropDegenerate(mesh, rep);
  if (mesh.triangles.size() < 4) throw InputError(file, key, "fewer than 4 non-degenerate triangles: no volume");
  checkEdgeTopology(mesh, file, key);
  orientOutwardAndMeasure(mesh, file, key, rep);
  rep.self_intersecting_faces = requireFewSelfIntersections(mesh, file, key, max_self_intersecting_fraction);
  rep.repairs = describeRepairs(rep);
  return rep;
}

}  // namespace inc
