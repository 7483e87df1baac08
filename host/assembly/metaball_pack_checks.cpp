// Packer input validation: welding, edge topology, orientation, volume and BVH triangle-triangle self-intersection.
#include "host/assembly/metaball_pack_checks.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <tuple>

#include "host/assembly/metaball_pack_bvh.h"
#include "model/input_error.h"

namespace inc {
namespace {

using pack::Aabb;

Vec3d unit(const Vec3d& v) {
  const double l = norm(v);
  return l > 0.0 ? v * (1.0 / l) : Vec3d{};
}

// Interval of the projections onto `dir` of the part of triangle p[] lying in the plane (distances d[]).
bool planeInterval(const Vec3d p[3], const double d[3], const Vec3d& dir, double eps, double& lo, double& hi) {
  lo = std::numeric_limits<double>::infinity();
  hi = -lo;
  bool any = false;
  for (int i = 0; i < 3; ++i) {
    if (std::fabs(d[i]) <= eps) {
      const double s = dot(p[i], dir);
      lo = std::min(lo, s);
      hi = std::max(hi, s);
      any = true;
    }
    const int j = (i + 1) % 3;
    if ((d[i] > eps && d[j] < -eps) || (d[i] < -eps && d[j] > eps)) {
      const Vec3d x = p[i] + (p[j] - p[i]) * (d[i] / (d[i] - d[j]));
      const double s = dot(x, dir);
      lo = std::min(lo, s);
      hi = std::max(hi, s);
      any = true;
    }
  }
  return any;
}

double orient2(const double a[2], const double b[2], const double c[2]) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

// Coplanar triangles: proper edge crossings or a vertex strictly inside the other triangle.
bool coplanarOverlap(const Vec3d p[3], const Vec3d q[3], const Vec3d& n, double eps2) {
  const int drop = (std::fabs(n.x) >= std::fabs(n.y) && std::fabs(n.x) >= std::fabs(n.z))
                       ? 0
                       : (std::fabs(n.y) >= std::fabs(n.z) ? 1 : 2);
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  double P[3][2], Q[3][2];
  for (int i = 0; i < 3; ++i) {
    P[i][0] = p[i][u];
    P[i][1] = p[i][v];
    Q[i][0] = q[i][u];
    Q[i][1] = q[i][v];
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double* a = P[i];
      const double* b = P[(i + 1) % 3];
      const double* c = Q[j];
      const double* d = Q[(j + 1) % 3];
      const double o1 = orient2(a, b, c), o2 = orient2(a, b, d), o3 = orient2(c, d, a), o4 = orient2(c, d, b);
      if (((o1 > eps2 && o2 < -eps2) || (o1 < -eps2 && o2 > eps2)) &&
          ((o3 > eps2 && o4 < -eps2) || (o3 < -eps2 && o4 > eps2)))
        return true;
    }
  auto strictlyInside = [&](const double x[2], double T[3][2]) {
    const double s = orient2(T[0], T[1], T[2]) > 0.0 ? 1.0 : -1.0;
    for (int k = 0; k < 3; ++k)
      if (s * orient2(T[k], T[(k + 1) % 3], x) <= eps2) return false;
    return true;
  };
  for (int i = 0; i < 3; ++i)
    if (strictlyInside(P[i], Q) || strictlyInside(Q[i], P)) return true;
  return false;
}

// Triangles without a common vertex.
bool trianglesIntersect(const Vec3d p[3], const Vec3d q[3], double eps, double eps2) {
  const Vec3d np = unit(cross(p[1] - p[0], p[2] - p[0]));
  const Vec3d nq = unit(cross(q[1] - q[0], q[2] - q[0]));
  double dq[3], dp[3];
  for (int i = 0; i < 3; ++i) dq[i] = dot(q[i] - p[0], np);
  if ((dq[0] > eps && dq[1] > eps && dq[2] > eps) || (dq[0] < -eps && dq[1] < -eps && dq[2] < -eps)) return false;
  for (int i = 0; i < 3; ++i) dp[i] = dot(p[i] - q[0], nq);
  if ((dp[0] > eps && dp[1] > eps && dp[2] > eps) || (dp[0] < -eps && dp[1] < -eps && dp[2] < -eps)) return false;
  const Vec3d dir = cross(np, nq);
  if (norm(dir) < 1e-12 || (std::fabs(dq[0]) <= eps && std::fabs(dq[1]) <= eps && std::fabs(dq[2]) <= eps))
    return coplanarOverlap(p, q, norm2(np) > 0.0 ? np : nq, eps2);
  double plo, phi, qlo, qhi;
  if (!planeInterval(p, dp, dir, eps, plo, phi) || !planeInterval(q, dq, dir, eps, qlo, qhi)) return false;
  return std::min(phi, qhi) - std::max(plo, qlo) > eps;  // a proper overlap, not a single touching point
}

// Segment ab against triangle t (a plane crossing strictly inside the triangle).
bool segmentPiercesTriangle(const Vec3d& a, const Vec3d& b, const Vec3d t[3], double eps, double eps2) {
  const Vec3d n = unit(cross(t[1] - t[0], t[2] - t[0]));
  if (norm2(n) == 0.0) return false;
  const double da = dot(a - t[0], n), db = dot(b - t[0], n);
  if (!((da > eps && db < -eps) || (da < -eps && db > eps))) return false;
  const Vec3d x = a + (b - a) * (da / (da - db));
  for (int k = 0; k < 3; ++k)
    if (dot(cross(t[(k + 1) % 3] - t[k], x - t[k]), n) <= eps2) return false;
  return true;
}

std::string edgeName(int a, int b) { return "edge (" + std::to_string(a) + ", " + std::to_string(b) + ")"; }

}  // namespace

std::vector<std::array<int, 2>> findSelfIntersections(const TriangleMesh& mesh, std::size_t max_pairs) {
  std::vector<std::array<int, 2>> found;
  if (mesh.triangles.empty()) return found;
  pack::TriangleBvh bvh(mesh);
  const double L = norm(bvh.bounds().extent());
  const double eps = 1e-10 * L, eps2 = 1e-12 * L * L;
  const auto& V = mesh.vertices;
  const auto& F = mesh.triangles;
  for (std::size_t t = 0; t < F.size() && found.size() < max_pairs; ++t) {
    Aabb box;
    for (int k = 0; k < 3; ++k) box.grow(V[std::size_t(F[t][std::size_t(k)])]);
    box.lo -= Vec3d{eps, eps, eps};
    box.hi += Vec3d{eps, eps, eps};
    std::vector<int> hits;
    bvh.overlapping(box, [&](int u) {
      if (u > int(t)) hits.push_back(u);
    });
    std::sort(hits.begin(), hits.end());
    for (int u : hits) {
      if (found.size() >= max_pairs) break;
      const auto& A = F[t];
      const auto& B = F[std::size_t(u)];
      int shared = 0, ia = -1, ib = -1;  // indices (within A, B) of a shared vertex
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (A[std::size_t(i)] == B[std::size_t(j)]) {
            ++shared;
            ia = i;
            ib = j;
          }
      const Vec3d p[3] = {V[std::size_t(A[0])], V[std::size_t(A[1])], V[std::size_t(A[2])]};
      const Vec3d q[3] = {V[std::size_t(B[0])], V[std::size_t(B[1])], V[std::size_t(B[2])]};
      bool hit = false;
      if (shared == 0) {
        hit = trianglesIntersect(p, q, eps, eps2);
      } else if (shared == 1) {
        // The edge opposite the shared vertex of each triangle must not pierce the other one.
        hit = segmentPiercesTriangle(p[(ia + 1) % 3], p[(ia + 2) % 3], q, eps, eps2) ||
              segmentPiercesTriangle(q[(ib + 1) % 3], q[(ib + 2) % 3], p, eps, eps2);
      } else if (shared == 2) {
        // Neighbours across an edge intersect beyond it only when folded flat onto each other.
        const Vec3d np = unit(cross(p[1] - p[0], p[2] - p[0])), nq = unit(cross(q[1] - q[0], q[2] - q[0]));
        hit = norm2(np) > 0.0 && norm2(nq) > 0.0 && dot(np, nq) < -(1.0 - 1e-10);
      }  // shared == 3: a duplicated triangle, reported by the edge checks as non-manifold
      if (hit) found.push_back({int(t), u});
    }
  }
  return found;
}

namespace {

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
  Aabb box;
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

// Rejects self-intersection beyond the tolerated fraction of faces; counts the tolerated faces in `rep`.
void checkSelfIntersections(const TriangleMesh& mesh, const std::string& file, const std::string& key,
                            double max_self_intersecting_fraction, PackInputReport& rep) {
  const std::size_t allowed_faces =
      std::size_t(std::max(0.0, max_self_intersecting_fraction) * double(mesh.triangles.size()));
  // Enough pairs to know whether the involved faces exceed the allowance (each pair adds at most two).
  const auto pairs = findSelfIntersections(mesh, std::max<std::size_t>(4, allowed_faces + 1));
  if (pairs.empty()) return;
  std::vector<int> faces;
  for (const auto& pr : pairs) {
    faces.push_back(pr[0]);
    faces.push_back(pr[1]);
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  if (faces.size() > allowed_faces || pairs.size() > allowed_faces) {
    std::ostringstream s;
    s << "self-intersecting surface: faces " << pairs[0][0] << " and " << pairs[0][1] << " intersect";
    if (pairs.size() > 1) s << " (and at least " << pairs.size() - 1 << " more pair(s))";
    s << "; not repaired: resolving intersections changes the shape";
    if (max_self_intersecting_fraction > 0.0)
      s << " (more than the tolerated fraction " << max_self_intersecting_fraction << " of faces)";
    throw InputError(file, key, s.str());
  }
  rep.self_intersecting_faces = int(faces.size());
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
  checkSelfIntersections(mesh, file, key, max_self_intersecting_fraction, rep);
  rep.repairs = describeRepairs(rep);
  return rep;
}

}  // namespace inc
