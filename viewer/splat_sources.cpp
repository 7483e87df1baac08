// Splat clouds from surface meshes (oriented discs) and particle sets (view-facing discs).
#include "viewer/splat_sources.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "viewer/surface_renderer.h"

namespace inc::viewer {

SplatCloud surfaceSplats(const TriangleMesh& mesh, const std::array<float, 3>& colour) {
  SplatCloud c;
  c.centers = mesh.vertices;
  c.normals = vertexNormals(mesh);
  c.radii.assign(mesh.vertices.size(), 0.0);
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const double e = norm(mesh.vertices[t[k]] - mesh.vertices[t[(k + 1) % 3]]);
      c.radii[t[k]] = std::max(c.radii[t[k]], 0.7 * e);
      c.radii[t[(k + 1) % 3]] = std::max(c.radii[t[(k + 1) % 3]], 0.7 * e);
    }
  c.colours.assign(mesh.vertices.size(), colour);
  return c;
}

bool pointBounds(const std::vector<Vec3d>& points, Vec3d& lo, Vec3d& hi) {
  bool any = false;
  for (const auto& p : points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    if (!any) {
      lo = hi = p;
      any = true;
    }
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  }
  return any;
}

double medianNearestSpacing(const std::vector<Vec3d>& points, std::size_t samples) {
  const std::size_t n = points.size();
  if (n < 2 || samples == 0) return 0.0;
  const std::size_t m = std::min(samples, n);
  std::vector<double> d;
  d.reserve(m);
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t i = k * n / m;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < n; ++j)
      if (j != i) best = std::min(best, norm2(points[j] - points[i]));
    if (std::isfinite(best)) d.push_back(std::sqrt(best));
  }
  if (d.empty()) return 0.0;
  std::nth_element(d.begin(), d.begin() + std::ptrdiff_t(d.size() / 2), d.end());
  return d[d.size() / 2];
}

SplatCloud particleSplats(const std::vector<Vec3d>& points, double radius_m, const std::array<float, 3>& colour) {
  SplatCloud c;
  if (radius_m <= 0.0) {
    Vec3d lo, hi;
    if (pointBounds(points, lo, hi)) {
      const Vec3d ext = hi - lo;
      // Flat or linear sets: use the largest extent so the volume is not zero.
      const double big = std::max({ext.x, ext.y, ext.z, 1e-9});
      const double vol = std::max(ext.x, 1e-3 * big) * std::max(ext.y, 1e-3 * big) * std::max(ext.z, 1e-3 * big);
      radius_m = 0.6 * std::cbrt(vol / double(std::max<std::size_t>(points.size(), 1)));
    } else {
      radius_m = 1e-3;
    }
  }
  c.centers = points;
  c.normals.assign(points.size(), Vec3d{0, 0, 0});
  c.radii.assign(points.size(), radius_m);
  c.colours.assign(points.size(), colour);
  return c;
}

}  // namespace inc::viewer
