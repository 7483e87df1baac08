// Test fixtures for the swept-surface mesh split: arc and straight blade sweeps, piece checks, polyline areas.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "host/cut/cut_surface_split.h"
#include "host/cut/cut_swept_surface.h"
#include "host/io/mesh.h"

namespace inc::cuttest {

// A blade parallel to z (from z0 to z1) whose centre runs along the circle of radius r about (cx, cy) in the
// xy-plane from angle a0 to a1 (rad) in `steps` strips. For a1 > a0 the strip's normal (motion x blade) points
// away from the circle's centre: the + side is outside the circle.
inline SweptSurface arcSweep(double cx, double cy, double r, double a0, double a1, int steps, double z0, double z1) {
  std::vector<BladePose> poses;
  for (int k = 0; k <= steps; ++k) {
    const double a = a0 + (a1 - a0) * k / steps;
    const Vec3d c(cx + r * std::cos(a), cy + r * std::sin(a), 0.0);
    poses.push_back({c + Vec3d(0, 0, z0), c + Vec3d(0, 0, z1)});
  }
  return sweepSurface(poses);
}

// A blade from base to tip translated by `motion` in `steps` strips.
inline SweptSurface straightBladeSweep(const Vec3d& base, const Vec3d& tip, const Vec3d& motion, int steps = 4) {
  std::vector<BladePose> poses;
  for (int k = 0; k <= steps; ++k)
    poses.push_back({base + motion * (double(k) / steps), tip + motion * (double(k) / steps)});
  return sweepSurface(poses);
}

// Closed (no boundary or non-manifold edge), manifold at every vertex, consistently oriented, no degenerate
// triangle; returns the report.
inline MeshReport expectClosedManifold(const TriangleMesh& m, const std::string& what) {
  const MeshReport r = analyzeMesh(m);
  EXPECT_EQ(r.boundary_edges, 0) << what;
  EXPECT_EQ(r.non_manifold_edges, 0) << what;
  EXPECT_EQ(r.inconsistent_edges, 0) << what;
  EXPECT_EQ(r.degenerate_triangles, 0) << what;
  EXPECT_EQ(nonManifoldVertexCount(m), 0) << what;
  return r;
}

// The connected components of a mesh as separate meshes (over shared vertices).
inline std::vector<TriangleMesh> meshComponents(const TriangleMesh& m) {
  std::vector<int> parent(m.vertices.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = int(i);
  const auto find = [&](int x) {
    while (parent[std::size_t(x)] != x) x = parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
    return x;
  };
  for (const auto& t : m.triangles) {
    parent[std::size_t(find(t[0]))] = find(t[1]);
    parent[std::size_t(find(t[1]))] = find(t[2]);
  }
  std::vector<int> comp_of(m.vertices.size(), -1), remap(m.vertices.size(), -1);
  std::vector<TriangleMesh> out;
  for (const auto& t : m.triangles) {
    const int root = find(t[0]);
    if (comp_of[std::size_t(root)] < 0) {
      comp_of[std::size_t(root)] = int(out.size());
      out.emplace_back();
    }
    TriangleMesh& c = out[std::size_t(comp_of[std::size_t(root)])];
    std::array<int, 3> tri;
    for (int k = 0; k < 3; ++k) {
      int& id = remap[std::size_t(t[k])];
      if (id < 0) {
        id = int(c.vertices.size());
        c.vertices.push_back(m.vertices[std::size_t(t[k])]);
      }
      tri[k] = id;
    }
    c.triangles.push_back(tri);
  }
  return out;
}

// Integral over y in [y0, y1] of x(y) along the polyline (x_k, y_k), y strictly increasing and covering [y0, y1]
// (exact for the piecewise-linear curve).
inline double polylineIntegral(const std::vector<double>& xs, const std::vector<double>& ys, double y0, double y1) {
  double sum = 0.0;
  for (std::size_t k = 0; k + 1 < xs.size(); ++k) {
    const double a = std::max(y0, ys[k]), b = std::min(y1, ys[k + 1]);
    if (b <= a) continue;
    const auto x = [&](double y) { return xs[k] + (xs[k + 1] - xs[k]) * (y - ys[k]) / (ys[k + 1] - ys[k]); };
    sum += 0.5 * (x(a) + x(b)) * (b - a);
  }
  return sum;
}

}  // namespace inc::cuttest
