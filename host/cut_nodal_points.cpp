// Cut spheres -> nodal points (uniform lattice, m/n each), visibility-filtered MLS supports, greedy re-packing.
#include "host/cut_nodal_points.h"

#include <algorithm>
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
                          double converted_max_radius, const RepackOptions& options) {
  const std::size_t np = p.size();
  if (np == 0) return 0;
  const double r_min = std::max(1e-9, options.min_radius_factor * p.spacing);
  const double r_max = std::max(r_min, options.max_radius > 0.0 ? options.max_radius : converted_max_radius);
  std::vector<double> clearance(np);
  for (std::size_t i = 0; i < np; ++i) clearance[i] = distanceToSweptSurface(surface, p.positions[i]);
  std::vector<std::size_t> order(np);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return clearance[a] > clearance[b]; });
  std::vector<char> covered(np, 0);
  const std::size_t first_new = spheres.size();
  for (std::size_t oi : order) {
    if (covered[oi]) continue;
    Vec3d c = p.positions[oi];
    double rad = std::min(clearance[oi], r_max);
    if (clearance[oi] < r_min) {
      Vec3d k, nrm;
      closestOnSweptSurface(surface, c, k, nrm);
      const Vec3d away = c - k;
      const double len = norm(away);
      const Vec3d u = len > 1e-12 * r_min ? away * (1.0 / len) : nrm * double(p.side[oi]);
      c = k + u * r_min;
      rad = r_min;
    }
    double mass = p.masses[oi];
    covered[oi] = 1;
    for (std::size_t j = 0; j < np; ++j) {
      if (covered[j] || p.side[j] != p.side[oi]) continue;
      if (norm2(p.positions[j] - c) >= rad * rad) continue;
      covered[j] = 1;
      mass += p.masses[j];
    }
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
      spheres.links.push_back({std::int32_t(j), std::int32_t(i)});
      spheres.link_rest_lengths.push_back(d);
    }
  return total - first_new;
}

}  // namespace inc
