// Self-intersection search: BVH over triangle boxes, exact-with-tolerance triangle pair tests, and the refusal rule.
#include "host/io/mesh_self_intersection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "host/io/triangle_bvh.h"
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

int requireFewSelfIntersections(const TriangleMesh& mesh, const std::string& file, const std::string& key,
                                double tolerated_fraction) {
  const std::size_t allowed_faces = std::size_t(std::max(0.0, tolerated_fraction) * double(mesh.triangles.size()));
  // Enough pairs to know whether the involved faces exceed the allowance (each pair adds at most two).
  const auto pairs = findSelfIntersections(mesh, std::max<std::size_t>(4, allowed_faces + 1));
  if (pairs.empty()) return 0;
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
    if (tolerated_fraction > 0.0) s << " (more than the tolerated fraction " << tolerated_fraction << " of faces)";
    throw InputError(file, key, s.str());
  }
  return int(faces.size());
}

}  // namespace inc
