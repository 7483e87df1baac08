// Test fixtures for the cutting tests: a lattice metaball block and sphere-graph components.
#pragma once

#include <cmath>
#include <numeric>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/cut/cut_swept_surface.h"

namespace inc::cuttest {

// n_x * n_y * n_z spheres of radius 0.75 * spacing on a cubic lattice (spacing 0.01 m) centred at the origin;
// links between overlapping neighbours; masses = density * spacing^3 (the cell each sphere owns).
inline MetaballModel latticeBlock(int nx, int ny, int nz, double spacing = 0.01, double density = 1000.0) {
  MetaballModel m;
  const Vec3d o(-0.5 * (nx - 1) * spacing, -0.5 * (ny - 1) * spacing, -0.5 * (nz - 1) * spacing);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) {
        m.rest_centers.push_back(o + Vec3d(i * spacing, j * spacing, k * spacing));
        m.rest_radii.push_back(0.75 * spacing);
        m.masses.push_back(density * spacing * spacing * spacing);
      }
  for (std::size_t a = 0; a < m.size(); ++a)
    for (std::size_t b = a + 1; b < m.size(); ++b) {
      const double d = norm(m.rest_centers[a] - m.rest_centers[b]);
      if (d < m.rest_radii[a] + m.rest_radii[b]) {
        m.links.push_back({std::int32_t(a), std::int32_t(b)});
        m.link_rest_lengths.push_back(d);
      }
    }
  return m;
}

inline int linkComponents(const MetaballModel& m) {
  std::vector<int> parent(m.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& l : m.links) parent[find(l[0])] = find(l[1]);
  int c = 0;
  for (std::size_t i = 0; i < m.size(); ++i) c += find(int(i)) == int(i);
  return c;
}

// A blade along y (length 2 * half_len) at height z = 0 swept along x from x0 to x1 in `steps` poses.
inline SweptSurface straightSweep(double x0, double x1, double y0, double y1, int steps = 4) {
  std::vector<BladePose> poses;
  for (int k = 0; k <= steps; ++k) {
    const double x = x0 + (x1 - x0) * k / steps;
    poses.push_back({Vec3d(x, y0, 0.0), Vec3d(x, y1, 0.0)});
  }
  return sweepSurface(poses);
}

}  // namespace inc::cuttest
