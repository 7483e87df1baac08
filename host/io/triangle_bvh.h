// Triangle bounding-volume hierarchy: exact nearest point, signed distance by angle-weighted pseudonormals, box
// overlap.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "host/io/mesh.h"
#include "physics/vec3.h"

namespace inc::pack {

struct Aabb {
  Vec3d lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
  Vec3d hi{-std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
           -std::numeric_limits<double>::max()};
  void grow(const Vec3d& p) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = p[a] < lo[a] ? p[a] : lo[a];
      hi[a] = p[a] > hi[a] ? p[a] : hi[a];
    }
  }
  void grow(const Aabb& b) {
    grow(b.lo);
    grow(b.hi);
  }
  bool overlaps(const Aabb& b) const {
    return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y && lo.z <= b.hi.z && b.lo.z <= hi.z;
  }
  double distance2(const Vec3d& p) const {  // 0 inside
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) {
      const double e = p[a] < lo[a] ? lo[a] - p[a] : (p[a] > hi[a] ? p[a] - hi[a] : 0.0);
      d2 += e * e;
    }
    return d2;
  }
  Vec3d extent() const { return hi - lo; }
};

// Which part of a triangle the nearest point lies on: 0 face, 1..3 edges (v0v1, v1v2, v2v0), 4..6 vertices.
enum NearestFeature : int {
  kFace = 0,
  kEdge01 = 1,
  kEdge12 = 2,
  kEdge20 = 3,
  kVertex0 = 4,
  kVertex1 = 5,
  kVertex2 = 6
};

// Exact closest point of p on triangle (a, b, c) by Voronoi-region classification; zero-area triangles
// fall back to their closest edge.
Vec3d closestPointOnTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c, int& feature);

struct NearestHit {
  double distance2 = std::numeric_limits<double>::infinity();
  int triangle = -1;
  int feature = kFace;
  Vec3d point;
};

class TriangleBvh {
 public:
  TriangleBvh() = default;
  explicit TriangleBvh(const TriangleMesh& mesh);

  // Nearest surface point; `bound2` is an upper bound on the squared distance known in advance (it prunes
  // the search; pass infinity when unknown). Returns triangle -1 only when nothing lies within the bound.
  NearestHit nearest(const Vec3d& p, double bound2 = std::numeric_limits<double>::infinity()) const;

  // Calls visit(triangle) for every triangle whose box overlaps `box`.
  template <typename Visit>
  void overlapping(const Aabb& box, Visit&& visit) const {
    if (nodes_.empty()) return;
    int stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top) {
      const Node& n = nodes_[std::size_t(stack[--top])];
      if (!n.box.overlaps(box)) continue;
      if (n.count > 0) {
        for (int k = 0; k < n.count; ++k) {
          const int t = order_[std::size_t(n.first + k)];
          if (tri_box_[std::size_t(t)].overlaps(box)) visit(t);
        }
      } else {
        stack[top++] = n.first;
        stack[top++] = n.first + 1;
      }
    }
  }

  // Number of triangles the ray o + t d (t > 0) crosses (Moller-Trumbore, half-open barycentric tests).
  int countRayCrossings(const Vec3d& o, const Vec3d& d) const;

  const Aabb& bounds() const { return nodes_.front().box; }
  const std::vector<Vec3d>& vertices() const { return vertices_; }
  const std::vector<std::array<int, 3>>& triangles() const { return triangles_; }

 private:
  struct Node {
    Aabb box;
    int first = 0;  // leaf: first index into order_; inner: index of the left child (right = first + 1)
    int count = 0;  // leaf: number of triangles; inner: 0
  };
  void build(int node, int begin, int end, std::vector<Vec3d>& centroids, int depth);
  std::vector<Vec3d> vertices_;
  std::vector<std::array<int, 3>> triangles_;
  std::vector<Aabb> tri_box_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

// Signed distance to a closed, consistently outward-oriented, non-self-intersecting surface: positive
// outside. The sign comes from the angle-weighted pseudonormal of the nearest feature (face normal, sum of
// the two face normals at an edge, angle-weighted normal sum at a vertex), which is exact for such meshes
// (Baerentzen and Aanaes 2005).
class SurfaceDistance {
 public:
  explicit SurfaceDistance(const TriangleMesh& mesh);
  struct Result {
    double distance = 0.0;  // signed, mesh units
    Vec3d nearest;          // nearest surface point
  };
  Result signedDistance(const Vec3d& p, double bound = std::numeric_limits<double>::infinity()) const;
  const TriangleBvh& bvh() const { return bvh_; }

  // Inside test by ray parity: a majority vote over three rays in fixed, irrational directions, so that a ray
  // grazing an edge or a vertex, or crossing a small local self-intersection, is outvoted by the other two.
  bool insideByRays(const Vec3d& p) const;

 private:
  TriangleBvh bvh_;
  std::vector<Vec3d> face_normal_;                 // unit (zero for zero-area triangles)
  std::vector<std::array<Vec3d, 3>> edge_normal_;  // per triangle edge (01, 12, 20)
  std::vector<Vec3d> vertex_normal_;
};

}  // namespace inc::pack
