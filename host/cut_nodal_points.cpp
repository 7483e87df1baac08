// Cut spheres -> nodal points (uniform lattice, m/n each), visibility-filtered MLS supports, greedy re-packing.
#include "host/cut_nodal_points.h"

#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <numeric>

#include "cpu_fallback/neighbor_search_cpu.h"
#include "host/input_error.h"

namespace inc {

double totalMass(const MetaballModel& m) {
  double s = 0.0;
  for (double v : m.masses) s += v;
  return s;
}
double totalMass(const NodalPoints& p) {
  double s = 0.0;
  for (double v : p.masses) s += v;
  return s;
}

SphereCutResult cutSpheres(const MetaballModel& model, const SweptSurface& surface, const CutOptions& options) {
  if (options.samples_per_diameter < 1 || options.samples_per_diameter > 64)
    throw InputError("cut", "samples_per_diameter", "must be in [1, 64]");
  SphereCutResult r;
  r.cut = findCutSpheres(surface, model.rest_centers, model.rest_radii);
  std::vector<std::int32_t> new_index(model.size(), -1);
  {
    std::vector<char> is_cut(model.size(), 0);
    for (auto i : r.cut) is_cut[i] = 1;
    for (std::size_t i = 0; i < model.size(); ++i) {
      if (is_cut[i]) continue;
      new_index[i] = std::int32_t(r.kept.size());
      r.kept.push_back(std::int32_t(i));
      r.spheres.rest_centers.push_back(model.rest_centers[i]);
      r.spheres.rest_radii.push_back(model.rest_radii[i]);
      r.spheres.masses.push_back(model.masses[i]);
    }
  }
  for (std::size_t l = 0; l < model.links.size(); ++l) {
    const auto& e = model.links[l];
    const int a = new_index[e[0]], b = new_index[e[1]];
    if (a < 0 || b < 0 || segmentCrossesSweptSurface(surface, model.rest_centers[e[0]], model.rest_centers[e[1]])) {
      ++r.links_removed;
      continue;
    }
    r.spheres.links.push_back({std::min(a, b), std::max(a, b)});
    r.spheres.link_rest_lengths.push_back(model.link_rest_lengths[l]);
  }
  // Uniform sampling inside each cut sphere (section 5.1): cell centres of an n^3 lattice over the bounding cube.
  const int n = options.samples_per_diameter;
  double spacing = 0.0;
  for (auto i : r.cut) {
    const Vec3d c = model.rest_centers[i];
    const double rad = model.rest_radii[i];
    const double h = 2.0 * rad / n;
    spacing = std::max(spacing, h);
    std::vector<Vec3d> pts;
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b)
        for (int k = 0; k < n; ++k) {
          const Vec3d x = c + Vec3d(-rad + (a + 0.5) * h, -rad + (b + 0.5) * h, -rad + (k + 0.5) * h);
          if (norm2(x - c) < rad * rad) pts.push_back(x);
        }
    if (pts.empty()) pts.push_back(c);
    const double m = model.masses[i] / double(pts.size());
    for (const auto& x : pts) {
      r.points.positions.push_back(x);
      r.points.masses.push_back(m);
      r.points.source_sphere.push_back(i);
      r.points.side.push_back(std::int8_t(sideOfSweptSurface(surface, x)));
    }
  }
  r.points.spacing = spacing;
  return r;
}

NeighborLists visibleNodalNeighbours(const NodalPoints& p, double h, const SweptSurface& surface, std::size_t* removed) {
  if (!(h > 0.0)) throw InputError("cut", "support_radius", "must be positive");
  NeighborLists lists = cpu::GridNeighborSearch<double>(p.positions, h).querySelf(h);
  const std::size_t n = removeCrossingNeighbours(lists, p.positions, surface);
  if (removed) *removed = n;
  return lists;
}

std::size_t repackSpheres(MetaballModel& spheres, const NodalPoints& p, const SweptSurface& surface,
                          double converted_max_radius, const RepackOptions& options,
                          const std::vector<SweptSurface>& earlier) {
  const std::size_t np = p.size();
  if (np == 0) return 0;
  const double r_max = std::max(std::max(1e-9, p.spacing), options.max_radius > 0.0 ? options.max_radius : converted_max_radius);
  // One sphere per (side, cell) of a grid of cell size h = r_max / 0.75 (the lattice spacing that gave the
  // converted spheres their radius 0.75 h), so the re-packed region has the sphere density of the original one.
  const double cell = r_max / 0.75;
  std::map<std::vector<std::int64_t>, std::vector<std::size_t>> groups;  // ordered: deterministic
  for (std::size_t i = 0; i < np; ++i) {
    const Vec3d& x = p.positions[i];
    std::vector<std::int64_t> key{std::int64_t(std::floor(x.x / cell)), std::int64_t(std::floor(x.y / cell)),
                                  std::int64_t(std::floor(x.z / cell)), std::int64_t(p.side[i])};
    for (const auto& e : earlier) key.push_back(sideOfSweptSurface(e, x));
    groups[key].push_back(i);
  }
  const std::size_t first_new = spheres.size();
  for (const auto& g : groups) {
    double mass = 0.0;
    Vec3d c;
    for (std::size_t i : g.second) {
      mass += p.masses[i];
      c += p.positions[i] * p.masses[i];
    }
    c *= 1.0 / mass;  // the centroid of points on one side of a locally planar cut stays on that side
    double rad = 0.5 * r_max;
    for (std::size_t i : g.second) rad = std::max(rad, norm(p.positions[i] - c));
    spheres.rest_centers.push_back(c);
    spheres.rest_radii.push_back(rad);
    spheres.masses.push_back(mass);
  }
  // Links of the new spheres: overlap and no crossing of the cut (new spheres connect only to their own side).
  const std::size_t total = spheres.size();
  for (std::size_t i = first_new; i < total; ++i)
    for (std::size_t j = 0; j < i; ++j) {
      const double d = norm(spheres.rest_centers[i] - spheres.rest_centers[j]);
      if (!(d < spheres.rest_radii[i] + spheres.rest_radii[j])) continue;
      if (segmentCrossesSweptSurface(surface, spheres.rest_centers[i], spheres.rest_centers[j])) continue;
      bool across = false;
      for (std::size_t e = 0; e < earlier.size() && !across; ++e)
        across = segmentCrossesSweptSurface(earlier[e], spheres.rest_centers[i], spheres.rest_centers[j]);
      if (across) continue;
      spheres.links.push_back({std::int32_t(j), std::int32_t(i)});
      spheres.link_rest_lengths.push_back(d);
    }
  return total - first_new;
}

}  // namespace inc
