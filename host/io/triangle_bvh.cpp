// Triangle BVH (median split), exact point-triangle distance and pseudonormal signed distance.
#include "host/io/triangle_bvh.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace inc::pack {
namespace {

constexpr int kLeafSize = 4;

// Closest point of p on segment ab; t in [0, 1].
Vec3d closestOnSegment(const Vec3d& p, const Vec3d& a, const Vec3d& b, double& t) {
  const Vec3d ab = b - a;
  const double l2 = norm2(ab);
  t = l2 > 0.0 ? std::clamp(dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
  return a + ab * t;
}

}  // namespace

Vec3d closestPointOnTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c, int& feature) {
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    feature = kVertex0;
    return a;
  }
  const Vec3d bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) {
    feature = kVertex1;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 && d1 - d3 > 0.0) {
    feature = kEdge01;
    return a + ab * (d1 / (d1 - d3));
  }
  const Vec3d cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) {
    feature = kVertex2;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 && d2 - d6 > 0.0) {
    feature = kEdge20;
    return a + ac * (d2 / (d2 - d6));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 && (d4 - d3) + (d5 - d6) > 0.0) {
    feature = kEdge12;
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double sum = va + vb + vc;
  if (sum > 0.0) {
    feature = kFace;
    return a + ab * (vb / sum) + ac * (vc / sum);
  }
  // Zero-area (or numerically flat) triangle: the closest point lies on one of its edges.
  double t;
  Vec3d best = closestOnSegment(p, a, b, t);
  feature = t <= 0.0 ? kVertex0 : (t >= 1.0 ? kVertex1 : kEdge01);
  double best2 = norm2(p - best);
  const Vec3d q1 = closestOnSegment(p, b, c, t);
  if (norm2(p - q1) < best2) {
    best = q1;
    best2 = norm2(p - q1);
    feature = t <= 0.0 ? kVertex1 : (t >= 1.0 ? kVertex2 : kEdge12);
  }
  const Vec3d q2 = closestOnSegment(p, c, a, t);
  if (norm2(p - q2) < best2) {
    best = q2;
    feature = t <= 0.0 ? kVertex2 : (t >= 1.0 ? kVertex0 : kEdge20);
  }
  return best;
}

TriangleBvh::TriangleBvh(const TriangleMesh& mesh) : vertices_(mesh.vertices), triangles_(mesh.triangles) {
  const int n = int(triangles_.size());
  if (n == 0) return;
  tri_box_.resize(std::size_t(n));
  std::vector<Vec3d> centroids(static_cast<std::size_t>(n));
  order_.resize(std::size_t(n));
  for (int t = 0; t < n; ++t) {
    Aabb b;
    for (int k = 0; k < 3; ++k) b.grow(vertices_[std::size_t(triangles_[std::size_t(t)][std::size_t(k)])]);
    tri_box_[std::size_t(t)] = b;
    centroids[std::size_t(t)] = (b.lo + b.hi) * 0.5;
    order_[std::size_t(t)] = t;
  }
  nodes_.reserve(std::size_t(2 * (n / kLeafSize + 1)));
  nodes_.emplace_back();
  build(0, 0, n, centroids, 0);
}

void TriangleBvh::build(int node, int begin, int end, std::vector<Vec3d>& centroids, int depth) {
  Aabb box, cbox;
  for (int i = begin; i < end; ++i) {
    const int t = order_[std::size_t(i)];
    box.grow(tri_box_[std::size_t(t)]);
    cbox.grow(centroids[std::size_t(t)]);
  }
  nodes_[std::size_t(node)].box = box;
  if (end - begin <= kLeafSize || depth > 48) {
    nodes_[std::size_t(node)].first = begin;
    nodes_[std::size_t(node)].count = end - begin;
    return;
  }
  const Vec3d e = cbox.extent();
  const int axis = (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
  const int mid = (begin + end) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](int a, int b) { return centroids[std::size_t(a)][axis] < centroids[std::size_t(b)][axis]; });
  const int left = int(nodes_.size());
  nodes_.emplace_back();
  nodes_.emplace_back();
  nodes_[std::size_t(node)].first = left;
  nodes_[std::size_t(node)].count = 0;
  build(left, begin, mid, centroids, depth + 1);
  build(left + 1, mid, end, centroids, depth + 1);
}

NearestHit TriangleBvh::nearest(const Vec3d& p, double bound2) const {
  NearestHit best;
  best.distance2 = bound2;
  if (nodes_.empty()) return best;
  std::pair<int, double> stack[128];
  int top = 0;
  stack[top++] = {0, nodes_[0].box.distance2(p)};
  while (top) {
    const auto [ni, d2box] = stack[--top];
    if (d2box > best.distance2) continue;
    const Node& n = nodes_[std::size_t(ni)];
    if (n.count > 0) {
      for (int k = 0; k < n.count; ++k) {
        const int t = order_[std::size_t(n.first + k)];
        if (tri_box_[std::size_t(t)].distance2(p) > best.distance2) continue;
        const auto& tri = triangles_[std::size_t(t)];
        int feature;
        const Vec3d q = closestPointOnTriangle(p, vertices_[std::size_t(tri[0])], vertices_[std::size_t(tri[1])],
                                               vertices_[std::size_t(tri[2])], feature);
        const double d2 = norm2(p - q);
        if (d2 < best.distance2 || (best.triangle < 0 && d2 <= best.distance2)) {
          best.distance2 = d2;
          best.triangle = t;
          best.feature = feature;
          best.point = q;
        }
      }
    } else {
      const double dl = nodes_[std::size_t(n.first)].box.distance2(p);
      const double dr = nodes_[std::size_t(n.first + 1)].box.distance2(p);
      // Push the farther child first so the nearer one is searched first and tightens the bound.
      if (dl < dr) {
        stack[top++] = {n.first + 1, dr};
        stack[top++] = {n.first, dl};
      } else {
        stack[top++] = {n.first, dl};
        stack[top++] = {n.first + 1, dr};
      }
    }
  }
  return best;
}

int TriangleBvh::countRayCrossings(const Vec3d& o, const Vec3d& d) const {
  if (nodes_.empty()) return 0;
  Vec3d inv;
  for (int a = 0; a < 3; ++a) inv[a] = d[a] != 0.0 ? 1.0 / d[a] : std::numeric_limits<double>::infinity();
  auto hitsBox = [&](const Aabb& b) {
    double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0.0) {
        if (o[a] < b.lo[a] || o[a] > b.hi[a]) return false;
        continue;
      }
      double ta = (b.lo[a] - o[a]) * inv[a], tb = (b.hi[a] - o[a]) * inv[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (t0 > t1) return false;
    }
    return true;
  };
  int crossings = 0;
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top) {
    const Node& n = nodes_[std::size_t(stack[--top])];
    if (!hitsBox(n.box)) continue;
    if (n.count == 0) {
      stack[top++] = n.first;
      stack[top++] = n.first + 1;
      continue;
    }
    for (int k = 0; k < n.count; ++k) {
      const auto& tri = triangles_[std::size_t(order_[std::size_t(n.first + k)])];
      const Vec3d a = vertices_[std::size_t(tri[0])];
      const Vec3d e1 = vertices_[std::size_t(tri[1])] - a, e2 = vertices_[std::size_t(tri[2])] - a;
      const Vec3d pv = cross(d, e2);
      const double det = dot(e1, pv);
      if (det == 0.0) continue;  // ray parallel to the triangle's plane
      const double inv_det = 1.0 / det;
      const Vec3d tv = o - a;
      const double u = dot(tv, pv) * inv_det;
      if (u < 0.0 || u >= 1.0) continue;
      const Vec3d qv = cross(tv, e1);
      const double v = dot(d, qv) * inv_det;
      if (v < 0.0 || u + v >= 1.0) continue;
      if (dot(e2, qv) * inv_det > 0.0) ++crossings;
    }
  }
  return crossings;
}

SurfaceDistance::SurfaceDistance(const TriangleMesh& mesh) : bvh_(mesh) {
  const auto& V = mesh.vertices;
  const auto& F = mesh.triangles;
  face_normal_.resize(F.size());
  edge_normal_.resize(F.size());
  vertex_normal_.assign(V.size(), Vec3d{});
  std::map<std::pair<int, int>, Vec3d> edge_sum;
  for (std::size_t t = 0; t < F.size(); ++t) {
    const Vec3d a = V[std::size_t(F[t][0])], b = V[std::size_t(F[t][1])], c = V[std::size_t(F[t][2])];
    const Vec3d n = cross(b - a, c - a);
    const double len = norm(n);
    face_normal_[t] = len > 0.0 ? n * (1.0 / len) : Vec3d{};
    // Angle-weighted vertex pseudonormals.
    const Vec3d p[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      const Vec3d e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
      const double l1 = norm(e1), l2 = norm(e2);
      if (l1 > 0.0 && l2 > 0.0) {
        const double angle = std::acos(std::clamp(dot(e1, e2) / (l1 * l2), -1.0, 1.0));
        vertex_normal_[std::size_t(F[t][std::size_t(k)])] += face_normal_[t] * angle;
      }
      const int u = F[t][std::size_t(k)], v = F[t][std::size_t((k + 1) % 3)];
      edge_sum[{std::min(u, v), std::max(u, v)}] += face_normal_[t];
    }
  }
  for (std::size_t t = 0; t < F.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int u = F[t][std::size_t(k)], v = F[t][std::size_t((k + 1) % 3)];
      edge_normal_[t][std::size_t(k)] = edge_sum[{std::min(u, v), std::max(u, v)}];
    }
}

SurfaceDistance::Result SurfaceDistance::signedDistance(const Vec3d& p, double bound) const {
  const double b2 = std::isfinite(bound) ? bound * bound * (1.0 + 1e-12) + 1e-300 : bound;
  NearestHit hit = bvh_.nearest(p, b2);
  if (hit.triangle < 0) hit = bvh_.nearest(p);  // the bound was too tight (never for a Lipschitz bound)
  Result r;
  r.nearest = hit.point;
  const std::size_t t = std::size_t(hit.triangle);
  Vec3d pn;
  switch (hit.feature) {
    case kFace: pn = face_normal_[t]; break;
    case kEdge01: pn = edge_normal_[t][0]; break;
    case kEdge12: pn = edge_normal_[t][1]; break;
    case kEdge20: pn = edge_normal_[t][2]; break;
    default: pn = vertex_normal_[std::size_t(bvh_.triangles()[t][std::size_t(hit.feature - kVertex0)])]; break;
  }
  const double d = std::sqrt(hit.distance2);
  r.distance = dot(p - hit.point, pn) >= 0.0 ? d : -d;
  return r;
}

bool SurfaceDistance::insideByRays(const Vec3d& p) const {
  // Directions with irrational-looking components: no mesh axis or lattice plane is parallel to them.
  static const Vec3d kDirs[3] = {{0.8191520442889918, 0.4539904997395468, 0.3507556053865862},
                                 {-0.2873478855663454, 0.9076733711353459, -0.3059617310829767},
                                 {0.3255681544571567, -0.2249510543438651, -0.9183613517770219}};
  // The majority of three: when the first two agree, the third cannot change it (a cut's sampling asks this
  // for every candidate point).
  const int a = bvh_.countRayCrossings(p, kDirs[0]) & 1, b = bvh_.countRayCrossings(p, kDirs[1]) & 1;
  if (a == b) return a == 1;
  return (bvh_.countRayCrossings(p, kDirs[2]) & 1) == 1;
}

}  // namespace inc::pack
