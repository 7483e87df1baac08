// Algorithm 1: classify each group's nodal points, down-sample the medial ones (eq. 14), pack, merge, link.
#include "host/cut/cut_repack.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "base/parallel.h"
#include "model/input_error.h"
#include "host/assembly/point_grid.h"

namespace inc {

namespace {

constexpr int kMinInteriorNeighbours = 4;  // fewer visible neighbours: the point cannot be interior
constexpr std::size_t kMinGroupPoints = 4;  // smaller components are isolated points (merged, see below)

std::vector<std::vector<std::int32_t>> components(const NeighborLists& l, std::size_t n, const std::vector<std::uint8_t>& skip) {
  std::vector<std::int32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](std::int32_t a) {
    while (parent[std::size_t(a)] != a) a = parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];
    return a;
  };
  const auto skipped = [&](std::size_t i) { return !skip.empty() && skip[i]; };
  for (std::size_t q = 0; q < n; ++q) {
    if (skipped(q)) continue;
    for (std::int64_t k = l.offsets[q]; k < l.offsets[q + 1]; ++k) {
      if (skipped(std::size_t(l.indices[std::size_t(k)]))) continue;
      const std::int32_t a = find(std::int32_t(q)), b = find(l.indices[std::size_t(k)]);
      if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
    }
  }
  std::vector<std::int32_t> root_group(n, -1);
  std::vector<std::vector<std::int32_t>> groups;
  for (std::size_t i = 0; i < n; ++i) {  // groups in order of their lowest point: deterministic
    if (skipped(i)) continue;
    const std::int32_t r = find(std::int32_t(i));
    if (root_group[std::size_t(r)] < 0) {
      root_group[std::size_t(r)] = std::int32_t(groups.size());
      groups.emplace_back();
    }
    groups[std::size_t(root_group[std::size_t(r)])].push_back(std::int32_t(i));
  }
  return groups;
}

}  // namespace

RepackResult packNodalPoints(const RepackPoints& p, const SweptSurface& cut, const RepackSettings& s) {
  const char* f = "repack";
  const std::size_t n = p.size();
  if (p.mass.size() != n) throw InputError(f, "points", "one mass per point");
  if (!p.context.empty() && p.context.size() != n) throw InputError(f, "context", "one flag per point (or none)");
  if (s.max_radius < 0) throw InputError(f, "max_radius", "must be >= 0");
  if (p.visible.offsets.size() != n + 1) throw InputError(f, "visible", "needs one CSR offset per point plus one");
  if (!(p.spacing > 0) || !(p.support > 0)) throw InputError(f, "spacing", "spacing and support must be > 0");
  if (!(s.boundary_offset > 0 && s.boundary_offset < 1)) throw InputError(f, "boundary_offset", "must lie in (0, 1)");
  if (!(s.spacing_factor > 0)) throw InputError(f, "spacing_factor", "must be > 0");
  if (!(s.sphere_budget > 0)) throw InputError(f, "sphere_budget", "must be > 0");
  if (!(s.reference_mass > 0)) throw InputError(f, "reference_mass", "must be > 0");
  const auto isContext = [&](std::size_t i) { return !p.context.empty() && p.context[i]; };
  for (std::size_t i = 0; i < n; ++i)
    if (!isContext(i) && (!(p.mass[i] > 0) || !std::isfinite(p.mass[i])))
      throw InputError(f, "mass", "every point mass must be finite and > 0");
  RepackResult r;
  r.owner.assign(n, -1);
  r.point_class.assign(n, kRepackMiddle);
  if (n == 0) return r;
  const double h = p.spacing;
  const auto groups = components(p.visible, n, p.context);
  // The grids below cover the points' box; a cell count of a few per point bounds their memory and set-up.
  Vec3d lo = p.rest[0], hi = p.rest[0];
  for (const Vec3d& x : p.rest)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], x[k]), hi[k] = std::max(hi[k], x[k]);
  const std::size_t max_cells = 8 * n + 4096;
  const auto grid = [&](const std::vector<Vec3d>& x, double cell) { return PointGrid(x, lo, hi, cell, max_cells); };
  const SweptSurfaceQuery cut_query(cut);
  std::vector<SweptSurfaceQuery> earlier_queries;
  for (const SweptSurface* c : s.earlier_cuts) earlier_queries.emplace_back(*c);

  // 1. Boundary points.
  cpu::parallelFor(std::int64_t(n), [&](std::int64_t i) {
    const std::int64_t b = p.visible.offsets[std::size_t(i)], e = p.visible.offsets[std::size_t(i) + 1];
    bool boundary = e - b < kMinInteriorNeighbours;
    if (!boundary) {
      Vec3d m;
      for (std::int64_t k = b; k < e; ++k) m += p.rest[std::size_t(p.visible.indices[std::size_t(k)])];
      m = m * (1.0 / double(e - b)) - p.rest[std::size_t(i)];
      boundary = norm(m) > s.boundary_offset * p.support;
    }
    r.point_class[std::size_t(i)] = boundary ? kRepackBoundary : kRepackMiddle;
  });

  // 2. d_b: distance to the nearest boundary point (the tissue's surface near the points: context included).
  std::vector<double> depth(n, 0.0);
  {
    // Context points farther than a support from every packed point have incomplete neighbourhoods (their own
    // neighbours were not sampled): they would pass for boundary points. Only the near ones count.
    std::vector<char> near(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      if (isContext(i)) continue;
      near[i] = 1;
      for (std::int64_t k = p.visible.offsets[i]; k < p.visible.offsets[i + 1]; ++k) near[std::size_t(p.visible.indices[std::size_t(k)])] = 1;
    }
    std::vector<std::int32_t> bnd;
    for (std::size_t i = 0; i < n; ++i)
      if (near[i] && r.point_class[i] == kRepackBoundary) bnd.push_back(std::int32_t(i));
    if (!bnd.empty()) {
      PointGrid hash = grid(p.rest, p.support);
      for (std::int32_t i : bnd) hash.insert(i);
      cpu::parallelFor(std::int64_t(n), [&](std::int64_t i) {
        double d = 0.0;
        if (r.point_class[std::size_t(i)] != kRepackBoundary) hash.nearest(p.rest[std::size_t(i)], d);
        depth[std::size_t(i)] = d;
      });
    }
  }
  std::vector<std::size_t> isolated;  // groups too small to hold a sphere of their own
  r.spacing_min = std::numeric_limits<double>::infinity();
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const auto& pts = groups[g];
    if (pts.size() < kMinGroupPoints) {
      isolated.push_back(g);
      continue;
    }
    ++r.groups;
    std::vector<std::int32_t> medial;
    for (std::int32_t i : pts) {
      if (r.point_class[std::size_t(i)] == kRepackBoundary) continue;
      double top = 0.0;
      for (std::int64_t k = p.visible.offsets[std::size_t(i)]; k < p.visible.offsets[std::size_t(i) + 1]; ++k)
        if (!isContext(std::size_t(p.visible.indices[std::size_t(k)])))
          top = std::max(top, depth[std::size_t(p.visible.indices[std::size_t(k)])]);
      if (depth[std::size_t(i)] >= top - 0.25 * h) {
        r.point_class[std::size_t(i)] = kRepackMedial;
        medial.push_back(i);
      }
    }
    if (medial.empty()) medial = pts;  // a sliver with no interior point: every point is a candidate centre
    // 3. eq. 14: spacing from the medial points' distance to the cut (at least one lattice spacing).
    double smax = 0.0;
    for (std::int32_t i : medial) smax = std::max(smax, cut_query.distance(p.rest[std::size_t(i)]));
    double d = std::max(h, std::isfinite(smax) ? s.spacing_factor * smax : h);
    // Capped balls need a spacing well below their radius: at most 2/3 of the cap (the organ's own spacing when
    // the cap is 1.5 x its radius), or the re-packed regions thin out cut after cut.
    if (s.max_radius > 0) d = std::min(d, std::max(h, s.max_radius / 1.5));
    r.spacing_min = std::min(r.spacing_min, d);
    r.spacing_max = std::max(r.spacing_max, d);
    // 4. Algorithm 1: the deepest medial points first; a sphere wherever every accepted centre is farther than d.
    //    Then (our completion) the middle points by the same rule: where the medial surface's balls leave a part
    //    of the group farther than d from every centre (a corner between a cut wall and the organ's surface),
    //    a middle point takes a sphere there.
    const auto deeper = [&](std::int32_t a, std::int32_t b) { return depth[std::size_t(a)] > depth[std::size_t(b)]; };
    std::vector<std::int32_t> order = medial, middle;
    std::stable_sort(order.begin(), order.end(), deeper);
    for (std::int32_t i : pts)
      if (r.point_class[std::size_t(i)] == kRepackMiddle) middle.push_back(i);
    std::stable_sort(middle.begin(), middle.end(), deeper);
    order.insert(order.end(), middle.begin(), middle.end());
    const auto radiusAt = [&](std::int32_t i) {
      const double rad = std::max(depth[std::size_t(i)] + 0.5 * h, h);
      return s.max_radius > 0 ? std::min(rad, s.max_radius) : rad;
    };
    const auto pack = [&](double dd) {
      std::vector<std::int32_t> accepted;
      PointGrid centres = grid(p.rest, dd);
      for (std::int32_t i : order) {
        if (centres.anyWithin(p.rest[std::size_t(i)], dd)) continue;
        centres.insert(i);
        accepted.push_back(i);
      }
      return accepted;
    };
    std::vector<std::int32_t> accepted = pack(d);
    const std::size_t packed = accepted.size();
    r.packed += packed;
    // 5. Merging small spheres (the paper's future work): while the group holds more spheres than its budget, the
    //    spacing grows by 10 % and the packing is redone; the shallow (small) candidates go first, their points
    //    join the deeper neighbours' cells, and the survivors stay evenly spread.
    double gmass = 0.0;
    for (std::int32_t i : pts) gmass += p.mass[std::size_t(i)];
    const std::size_t budget =
        std::max<std::size_t>(1, std::size_t(std::ceil(s.sphere_budget * gmass / s.reference_mass - 1e-9)));
    double dd = d;
    for (int it = 0; accepted.size() > budget && it < 200; ++it) accepted = pack(dd *= 1.1);
    r.merged += packed - accepted.size();
    r.merge_spacing_max = std::max(r.merge_spacing_max, dd);
    // 6. Every point to its nearest centre (its Voronoi cell: the mass stays local); radius = the distance to the
    //    nearest boundary point plus half a spacing (Algorithm 1; the boundary points sit half a spacing inside the
    //    surface they sample), at least one spacing (a sliver without interior points), grown towards the cell's
    //    farthest point so that the balls cover the group, all within max_radius (uncapped, a ball reaching out
    //    of the tissue puts points, and mass, outside it when it is cut again, and the next balls grow further).
    const std::size_t first = r.centres.size();
    for (std::int32_t i : accepted) {
      r.centres.push_back(p.rest[std::size_t(i)]);
      r.radii.push_back(radiusAt(i));
      r.masses.push_back(0.0);
    }
    std::vector<std::int32_t> local(accepted.size());
    std::iota(local.begin(), local.end(), 0);
    PointGrid centres = grid(r.centres, dd);
    for (std::size_t k = 0; k < accepted.size(); ++k) centres.insert(std::int32_t(first + k));
    cpu::parallelFor(std::int64_t(pts.size()), [&](std::int64_t k) {
      double dist = 0.0;
      r.owner[std::size_t(pts[std::size_t(k)])] = centres.nearest(p.rest[std::size_t(pts[std::size_t(k)])], dist);
    });
    for (std::int32_t i : pts) {
      const std::size_t sphere = std::size_t(r.owner[std::size_t(i)]);
      r.masses[sphere] += p.mass[std::size_t(i)];
      const double reach = norm(p.rest[std::size_t(i)] - r.centres[sphere]);
      r.radii[sphere] = std::max(r.radii[sphere], s.max_radius > 0 ? std::min(reach, s.max_radius) : reach);
    }
  }
  // Isolated points (components of fewer than kMinGroupPoints, e.g. a fragment cut off a sphere): their mass goes
  // to the nearest new sphere whose centre they see (no cut between); with none in sight they become a small
  // debris sphere of their own (radius: one spacing, or up to its farthest point).
  for (std::size_t g : isolated) {
    const auto& pts = groups[g];
    for (std::int32_t i : pts) r.point_class[std::size_t(i)] = kRepackBoundary;
    const Vec3d& x0 = p.rest[std::size_t(pts.front())];
    std::int32_t best = -1;
    double bd = std::numeric_limits<double>::infinity();
    for (std::size_t q = 0; q < r.centres.size(); ++q) {
      const double dq = norm(r.centres[q] - x0);
      if (!(dq < bd)) continue;
      bool hidden = cut_query.segmentCrosses(x0, r.centres[q]);
      for (std::size_t c = 0; c < earlier_queries.size() && !hidden; ++c)
        hidden = earlier_queries[c].segmentCrosses(x0, r.centres[q]);
      if (!hidden) bd = dq, best = std::int32_t(q);
    }
    if (best < 0) {
      Vec3d c;
      double m = 0.0;
      for (std::int32_t i : pts) c += p.rest[std::size_t(i)] * p.mass[std::size_t(i)], m += p.mass[std::size_t(i)];
      best = std::int32_t(r.centres.size());
      r.centres.push_back(c * (1.0 / m));
      double rad = h;
      for (std::int32_t i : pts) rad = std::max(rad, norm(p.rest[std::size_t(i)] - r.centres.back()));
      r.radii.push_back(rad);
      r.masses.push_back(0.0);
    }
    for (std::int32_t i : pts) {
      r.owner[std::size_t(i)] = best;
      r.masses[std::size_t(best)] += p.mass[std::size_t(i)];
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (isContext(i)) continue;
    r.boundary += r.point_class[i] == kRepackBoundary;
    r.medial += r.point_class[i] == kRepackMedial;
    r.middle += r.point_class[i] == kRepackMiddle;
  }
  if (!std::isfinite(r.spacing_min)) r.spacing_min = r.spacing_max = 0.0;
  return r;
}

std::size_t appendRepackedSpheres(MetaballModel& spheres, const RepackResult& r, const std::vector<const SweptSurface*>& cuts) {
  const std::size_t first_new = spheres.size();
  for (std::size_t k = 0; k < r.centres.size(); ++k) {
    spheres.rest_centers.push_back(r.centres[k]);
    spheres.rest_radii.push_back(r.radii[k]);
    spheres.masses.push_back(r.masses[k]);
  }
  const std::size_t total = spheres.size();
  // Candidate pairs per new sphere, decided in parallel, appended in (i, j) order: deterministic.
  std::vector<SweptSurfaceQuery> queries;
  for (const SweptSurface* c : cuts) queries.emplace_back(*c);
  std::vector<std::vector<std::int32_t>> found(total - first_new);
  cpu::parallelFor(std::int64_t(total - first_new), [&](std::int64_t k) {
    const std::size_t i = first_new + std::size_t(k);
    for (std::size_t j = 0; j < i; ++j) {
      const double d = norm(spheres.rest_centers[i] - spheres.rest_centers[j]);
      if (!(d < spheres.rest_radii[i] + spheres.rest_radii[j]) || !(d > 0)) continue;
      bool across = false;
      for (std::size_t c = 0; c < queries.size() && !across; ++c)
        across = queries[c].segmentCrosses(spheres.rest_centers[i], spheres.rest_centers[j]);
      if (!across) found[std::size_t(k)].push_back(std::int32_t(j));
    }
  });
  std::size_t added = 0;
  for (std::size_t k = 0; k < found.size(); ++k)
    for (std::int32_t j : found[k]) {
      const std::size_t i = first_new + k;
      spheres.links.push_back({j, std::int32_t(i)});
      spheres.link_rest_lengths.push_back(norm(spheres.rest_centers[i] - spheres.rest_centers[std::size_t(j)]));
      ++added;
    }
  return added;
}

}  // namespace inc
