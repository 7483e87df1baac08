// Known geometry for the viewer tests: Fibonacci spheres of splats and an icosphere surface mesh.
#pragma once

#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "host/io/mesh.h"
#include "viewer/splat_raster.h"

namespace inc::viewer::testing {

// n points evenly spread on a sphere (golden-angle spiral), outward normals, splat radius
// `radius_factor` times the mean spacing sqrt(4 pi R^2 / n).
inline SplatCloud fibonacciSphere(int n, double radius_m, const Vec3d& center, double radius_factor = 1.0) {
  SplatCloud c;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  const double spacing = std::sqrt(4.0 * M_PI * radius_m * radius_m / n);
  for (int i = 0; i < n; ++i) {
    const double y = 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - y * y));
    const double phi = golden * i;
    const Vec3d dir{r * std::cos(phi), y, r * std::sin(phi)};
    c.centers.push_back(center + dir * radius_m);
    c.normals.push_back(dir);
    c.radii.push_back(radius_factor * spacing);
    c.colours.push_back({0.8f, 0.3f, 0.3f});
  }
  return c;
}

// Icosahedron subdivided `levels` times and projected on the sphere; outward counter-clockwise triangles.
inline TriangleMesh icosphere(int levels, double radius_m, const Vec3d& center) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3d> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p = p * (1.0 / norm(p));
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      Vec3d m = v[a] + v[b];
      v.push_back(m * (1.0 / norm(m)));
      mid[key] = int(v.size()) - 1;
      return int(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f.swap(g);
  }
  TriangleMesh m;
  for (const auto& p : v) m.vertices.push_back(center + p * radius_m);
  m.triangles = f;
  return m;
}

// Fraction of covered pixels in a SplatImage.
inline double coveredFraction(const SplatImage& img) {
  std::size_t n = 0;
  for (float w : img.weight) n += (w > 0.0f) ? 1 : 0;
  return double(n) / double(img.weight.size());
}

}  // namespace inc::viewer::testing
