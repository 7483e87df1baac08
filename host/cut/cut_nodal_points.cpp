// Cut spheres -> nodal points (uniform lattice, m/n each), visibility-filtered MLS supports, re-packing (Algorithm 1).
#include "host/cut/cut_nodal_points.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>

#include "base/parallel.h"
#include "cpu_fallback/neighbor_search_cpu.h"
#include "host/cut/cut_repack.h"
#include "model/input_error.h"

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

std::vector<Vec3d> sampleSphere(const Vec3d& c, double rad, int n, const std::vector<const SweptSurface*>& cuts,
                                const std::function<bool(const Vec3d&)>& inside) {
  if (n < 1 || n > 64) throw InputError("cut", "samples_per_diameter", "must be in [1, 64]");
  const double h = 2.0 * rad / n;
  std::vector<Vec3d> pts;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b)
      for (int k = 0; k < n; ++k) {
        const Vec3d x = c + Vec3d(-rad + (a + 0.5) * h, -rad + (b + 0.5) * h, -rad + (k + 0.5) * h);
        if (!(norm2(x - c) < rad * rad) || (inside && !inside(x))) continue;
        bool hidden = false;
        for (std::size_t q = 0; q < cuts.size() && !hidden; ++q) hidden = segmentCrossesSweptSurface(*cuts[q], c, x);
        if (!hidden) pts.push_back(x);
      }
  if (pts.empty()) pts.push_back(c);
  return pts;
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
    const std::vector<Vec3d> pts =
        sampleSphere(model.rest_centers[i], model.rest_radii[i], n, options.earlier_cuts, options.inside);
    spacing = std::max(spacing, 2.0 * model.rest_radii[i] / n);
    const double m = model.masses[i] / double(pts.size());
    for (const auto& x : pts) {
      r.points.positions.push_back(x);
      r.points.masses.push_back(m);
      r.points.source_sphere.push_back(i);
      r.points.side.push_back(std::int8_t(sideOfSweptSurface(surface, x)));
    }
  }
  r.points.spacing = spacing;
  for (auto i : r.cut) r.points.max_source_radius = std::max(r.points.max_source_radius, model.rest_radii[i]);
  return r;
}

namespace {

// Bounding box of a swept surface and of a point cloud, grown by `pad`; cuts that miss the cloud are skipped.
bool boxesOverlap(const SweptSurface& s, const std::vector<Vec3d>& x, double pad) {
  if (s.vertices.empty() || x.empty()) return false;
  Vec3d lo = s.vertices.front(), hi = lo, plo = x.front(), phi = plo;
  for (const auto& v : s.vertices)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
  for (const auto& v : x)
    for (int k = 0; k < 3; ++k) plo[k] = std::min(plo[k], v[k]), phi[k] = std::max(phi[k], v[k]);
  for (int k = 0; k < 3; ++k)
    if (hi[k] + pad < plo[k] || phi[k] + pad < lo[k]) return false;
  return true;
}

}  // namespace

namespace {

// Drops from symmetric `lists` every pair that crosses one of `cuts` (pairs at most `max_length` long): one pass
// over the unordered pairs (lower index first, the mirror entry copies the decision), each tested only against
// the cuts both its ends lie near (a pair no longer than L crosses a surface only when both ends are within L of
// it). Returns the number of directed entries dropped.
std::size_t removeCrossingPairs(NeighborLists& lists, const std::vector<Vec3d>& x,
                                const std::vector<const SweptSurface*>& all, double max_length) {
  const std::size_t nq = lists.queryCount();
  std::vector<const SweptSurface*> cuts;
  for (const SweptSurface* c : all)
    if (c && !c->empty() && boxesOverlap(*c, x, max_length)) cuts.push_back(c);
  if (cuts.empty() || lists.indices.empty()) return 0;
  const double reach = max_length * (1.0 + 1e-9) + 1e-12;
  std::vector<SweptSurfaceQuery> queries;
  queries.reserve(cuts.size());
  for (const SweptSurface* c : cuts) queries.emplace_back(*c);
  // Per point, the cuts it lies near (CSR).
  std::vector<std::vector<std::uint16_t>> near(nq);
  cpu::parallelFor(std::int64_t(nq), [&](std::int64_t q) {
    for (std::size_t c = 0; c < cuts.size(); ++c)
      if (queries[c].distance(x[std::size_t(q)]) <= reach) near[std::size_t(q)].push_back(std::uint16_t(c));
  });
  std::vector<char> keep(lists.indices.size(), 1);
  const auto decide = [&](std::size_t a, std::size_t b) {  // a < b
    return crossesACutNearBoth(near[a], near[b], queries, x[a], x[b]);
  };
  cpu::parallelFor(std::int64_t(nq), [&](std::int64_t q) {
    if (near[std::size_t(q)].empty()) return;
    for (std::int64_t k = lists.offsets[std::size_t(q)]; k < lists.offsets[std::size_t(q) + 1]; ++k) {
      const std::int32_t j = lists.indices[std::size_t(k)];
      if (j > q && !near[std::size_t(j)].empty() && decide(std::size_t(q), std::size_t(j))) keep[std::size_t(k)] = 0;
    }
  });
  // Mirror entries (j < q) copy the decision of (j, q), found in j's ascending list.
  cpu::parallelFor(std::int64_t(nq), [&](std::int64_t q) {
    if (near[std::size_t(q)].empty()) return;
    for (std::int64_t k = lists.offsets[std::size_t(q)]; k < lists.offsets[std::size_t(q) + 1]; ++k) {
      const std::int32_t j = lists.indices[std::size_t(k)];
      if (j >= q || near[std::size_t(j)].empty()) continue;
      const auto* first = lists.indices.data() + lists.offsets[std::size_t(j)];
      const auto* last = lists.indices.data() + lists.offsets[std::size_t(j) + 1];
      const auto* it = std::lower_bound(first, last, std::int32_t(q));
      keep[std::size_t(k)] = (it != last && *it == q) ? keep[std::size_t(it - lists.indices.data())]
                                                      : (decide(std::size_t(j), std::size_t(q)) ? 0 : 1);
    }
  });
  if (std::find(keep.begin(), keep.end(), 0) == keep.end()) return 0;
  NeighborLists out;
  out.offsets.assign(nq + 1, 0);
  out.indices.reserve(lists.indices.size());
  for (std::size_t q = 0; q < nq; ++q) {
    for (std::int64_t k = lists.offsets[q]; k < lists.offsets[q + 1]; ++k)
      if (keep[std::size_t(k)]) out.indices.push_back(lists.indices[std::size_t(k)]);
    out.offsets[q + 1] = std::int64_t(out.indices.size());
  }
  const std::size_t removed = lists.indices.size() - out.indices.size();
  lists = std::move(out);
  return removed;
}

}  // namespace

NeighborLists visibleSupports(const std::vector<Vec3d>& x, double h, const std::vector<const SweptSurface*>& cuts,
                              std::size_t* removed) {
  if (!(h > 0.0)) throw InputError("cut", "support_radius", "must be positive");
  NeighborLists lists;
  if (x.empty()) {
    lists.offsets.assign(1, 0);
  } else {
    lists = cpu::GridNeighborSearch<double>(x, h).querySelf(h);
  }
  const std::size_t total = removeCrossingPairs(lists, x, cuts, h);
  if (removed) *removed = total;
  return lists;
}

NeighborLists visibleNodalNeighbours(const NodalPoints& p, double h, const SweptSurface& surface,
                                     std::size_t* removed) {
  return visibleSupports(p.positions, h, {&surface}, removed);
}

std::size_t repackSpheres(MetaballModel& spheres, const NodalPoints& p, const SweptSurface& surface,
                          const RepackOptions& options, const std::vector<SweptSurface>& earlier) {
  const std::size_t np = p.size();
  if (np == 0) return 0;
  std::vector<const SweptSurface*> cuts{&surface};
  for (const auto& e : earlier) cuts.push_back(&e);
  RepackPoints rp;
  rp.rest = p.positions;
  rp.mass = p.masses;
  rp.context.assign(np, 0);
  rp.spacing = std::max(1e-9, p.spacing);
  rp.support = options.support_factor * rp.spacing;
  // Context: the spheres that stay and overlap the points (the interface spheres of the dissection model),
  // sampled at the same spacing and visible from their centres, so that the faces the points share with them are
  // not taken for the surface.
  {
    const cpu::GridNeighborSearch<double> grid(p.positions, rp.support);
    std::vector<double> reach(spheres.size());
    for (std::size_t j = 0; j < spheres.size(); ++j) reach[j] = spheres.rest_radii[j];
    const NeighborLists near = grid.query(spheres.rest_centers, reach);
    for (std::size_t j = 0; j < spheres.size(); ++j) {
      if (near.count(j) == 0) continue;
      const int n = std::clamp(int(std::lround(2.0 * spheres.rest_radii[j] / rp.spacing)), 2, 64);
      for (const Vec3d& x : sampleSphere(spheres.rest_centers[j], spheres.rest_radii[j], n, cuts)) {
        rp.rest.push_back(x);
        rp.mass.push_back(0.0);
        rp.context.push_back(1);
      }
    }
  }
  rp.visible = visibleSupports(rp.rest, rp.support, cuts);
  // Reference sphere: the mean mass of the converted spheres (each point knows its source sphere).
  std::vector<std::int32_t> sources(p.source_sphere.begin(), p.source_sphere.end());
  std::sort(sources.begin(), sources.end());
  const std::size_t converted = std::size_t(std::unique(sources.begin(), sources.end()) - sources.begin());
  RepackSettings s;
  s.boundary_offset = options.boundary_offset;
  s.spacing_factor = options.spacing_factor;
  s.sphere_budget = options.sphere_budget;
  s.reference_mass =
      options.reference_mass > 0 ? options.reference_mass : totalMass(p) / double(std::max<std::size_t>(1, converted));
  for (std::size_t k = 1; k < cuts.size(); ++k) s.earlier_cuts.push_back(cuts[k]);
  s.max_radius = options.max_radius > 0 ? options.max_radius : 1.5 * p.max_source_radius;
  const RepackResult r = packNodalPoints(rp, surface, s);
  appendRepackedSpheres(spheres, r, cuts);
  return r.centres.size();
}

}  // namespace inc
