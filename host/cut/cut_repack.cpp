// Algorithm 1: classify each group's nodal points, down-sample the medial ones (eq. 14), pack, merge, link.
#include "host/cut/cut_repack.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "base/parallel.h"
#include "host/assembly/point_grid.h"
#include "model/input_error.h"

namespace inc {

namespace {

constexpr int kMinInteriorNeighbours = 4;   // fewer visible neighbours: the point cannot be interior
constexpr std::size_t kMinGroupPoints = 4;  // smaller components are isolated points (merged, see below)

std::vector<std::vector<std::int32_t>> components(const NeighborLists& l, std::size_t n,
                                                  const std::vector<std::uint8_t>& skip) {
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

void checkRepackInput(const RepackPoints& p, const RepackSettings& s) {
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
  for (std::size_t i = 0; i < n; ++i)
    if (!(!p.context.empty() && p.context[i]) && (!(p.mass[i] > 0) || !std::isfinite(p.mass[i])))
      throw InputError(f, "mass", "every point mass must be finite and > 0");
}

// Algorithm 1 over one set of points (packNodalPoints), phase by phase; every phase writes into `r`.
class Repacker {
 public:
  Repacker(const RepackPoints& p, const SweptSurface& cut, const RepackSettings& s, RepackResult& r)
      : p_(p), s_(s), r_(r), n_(p.size()), h_(p.spacing), cut_query_(cut) {
    // The grids below cover the points' box; a cell count of a few per point bounds their memory and set-up.
    lo_ = hi_ = p.rest[0];
    for (const Vec3d& x : p.rest)
      for (int k = 0; k < 3; ++k) lo_[k] = std::min(lo_[k], x[k]), hi_[k] = std::max(hi_[k], x[k]);
    max_cells_ = 8 * n_ + 4096;
    for (const SweptSurface* c : s.earlier_cuts) earlier_queries_.emplace_back(*c);
  }

  void classifyBoundary();
  void measureDepth();
  void packGroup(const std::vector<std::int32_t>& pts);
  void absorbIsolated(const std::vector<std::int32_t>& pts);
  void countClasses();

 private:
  bool isContext(std::size_t i) const { return !p_.context.empty() && p_.context[i]; }
  PointGrid grid(const std::vector<Vec3d>& x, double cell) const { return PointGrid(x, lo_, hi_, cell, max_cells_); }
  std::vector<std::int32_t> medialPoints(const std::vector<std::int32_t>& pts);
  double groupSpacing(const std::vector<std::int32_t>& medial) const;
  std::vector<std::int32_t> packingOrder(const std::vector<std::int32_t>& medial,
                                         const std::vector<std::int32_t>& pts) const;
  std::vector<std::int32_t> packCentres(const std::vector<std::int32_t>& order, double d) const;
  void assignCells(const std::vector<std::int32_t>& pts, const std::vector<std::int32_t>& accepted, double d);
  std::int32_t visibleCentre(const Vec3d& x0) const;

  const RepackPoints& p_;
  const RepackSettings& s_;
  RepackResult& r_;
  const std::size_t n_;
  const double h_;  // the lattice spacing (m)
  Vec3d lo_, hi_;
  std::size_t max_cells_ = 0;
  const SweptSurfaceQuery cut_query_;
  std::vector<SweptSurfaceQuery> earlier_queries_;
  std::vector<double> depth_;  // d_b per point (m)
};

// 1. Boundary points.
void Repacker::classifyBoundary() {
  cpu::parallelFor(std::int64_t(n_), [&](std::int64_t i) {
    const std::int64_t b = p_.visible.offsets[std::size_t(i)], e = p_.visible.offsets[std::size_t(i) + 1];
    bool boundary = e - b < kMinInteriorNeighbours;
    if (!boundary) {
      Vec3d m;
      for (std::int64_t k = b; k < e; ++k) m += p_.rest[std::size_t(p_.visible.indices[std::size_t(k)])];
      m = m * (1.0 / double(e - b)) - p_.rest[std::size_t(i)];
      boundary = norm(m) > s_.boundary_offset * p_.support;
    }
    r_.point_class[std::size_t(i)] = boundary ? kRepackBoundary : kRepackMiddle;
  });
}

// 2. d_b: distance to the nearest boundary point (the tissue's surface near the points: context included).
void Repacker::measureDepth() {
  depth_.assign(n_, 0.0);
  // Context points farther than a support from every packed point have incomplete neighbourhoods (their own
  // neighbours were not sampled): they would pass for boundary points. Only the near ones count.
  std::vector<char> near(n_, 0);
  for (std::size_t i = 0; i < n_; ++i) {
    if (isContext(i)) continue;
    near[i] = 1;
    for (std::int64_t k = p_.visible.offsets[i]; k < p_.visible.offsets[i + 1]; ++k)
      near[std::size_t(p_.visible.indices[std::size_t(k)])] = 1;
  }
  std::vector<std::int32_t> bnd;
  for (std::size_t i = 0; i < n_; ++i)
    if (near[i] && r_.point_class[i] == kRepackBoundary) bnd.push_back(std::int32_t(i));
  if (bnd.empty()) return;
  PointGrid hash = grid(p_.rest, p_.support);
  for (std::int32_t i : bnd) hash.insert(i);
  cpu::parallelFor(std::int64_t(n_), [&](std::int64_t i) {
    double d = 0.0;
    if (r_.point_class[std::size_t(i)] != kRepackBoundary) hash.nearest(p_.rest[std::size_t(i)], d);
    depth_[std::size_t(i)] = d;
  });
}

// Steps 2-6 for one group (a component of at least kMinGroupPoints points).
void Repacker::packGroup(const std::vector<std::int32_t>& pts) {
  ++r_.groups;
  std::vector<std::int32_t> medial = medialPoints(pts);
  if (medial.empty()) medial = pts;  // a sliver with no interior point: every point is a candidate centre
  const double d = groupSpacing(medial);
  r_.spacing_min = std::min(r_.spacing_min, d);
  r_.spacing_max = std::max(r_.spacing_max, d);
  const std::vector<std::int32_t> order = packingOrder(medial, pts);
  std::vector<std::int32_t> accepted = packCentres(order, d);
  const std::size_t packed = accepted.size();
  r_.packed += packed;
  // 5. Merging small spheres (the paper's future work): while the group holds more spheres than its budget, the
  //    spacing grows by 10 % and the packing is redone; the shallow (small) candidates go first, their points
  //    join the deeper neighbours' cells, and the survivors stay evenly spread.
  double gmass = 0.0;
  for (std::int32_t i : pts) gmass += p_.mass[std::size_t(i)];
  const std::size_t budget =
      std::max<std::size_t>(1, std::size_t(std::ceil(s_.sphere_budget * gmass / s_.reference_mass - 1e-9)));
  double dd = d;
  for (int it = 0; accepted.size() > budget && it < 200; ++it) accepted = packCentres(order, dd *= 1.1);
  r_.merged += packed - accepted.size();
  r_.merge_spacing_max = std::max(r_.merge_spacing_max, dd);
  assignCells(pts, accepted, dd);
}

// 2. (continued) The group's medial points: non-boundary points whose d_b is within a quarter spacing of the
// largest among their visible neighbours that are not context.
std::vector<std::int32_t> Repacker::medialPoints(const std::vector<std::int32_t>& pts) {
  std::vector<std::int32_t> medial;
  for (std::int32_t i : pts) {
    if (r_.point_class[std::size_t(i)] == kRepackBoundary) continue;
    double top = 0.0;
    for (std::int64_t k = p_.visible.offsets[std::size_t(i)]; k < p_.visible.offsets[std::size_t(i) + 1]; ++k)
      if (!isContext(std::size_t(p_.visible.indices[std::size_t(k)])))
        top = std::max(top, depth_[std::size_t(p_.visible.indices[std::size_t(k)])]);
    if (depth_[std::size_t(i)] >= top - 0.25 * h_) {
      r_.point_class[std::size_t(i)] = kRepackMedial;
      medial.push_back(i);
    }
  }
  return medial;
}

// 3. eq. 14: spacing from the medial points' distance to the cut (at least one lattice spacing).
double Repacker::groupSpacing(const std::vector<std::int32_t>& medial) const {
  double smax = 0.0;
  for (std::int32_t i : medial) smax = std::max(smax, cut_query_.distance(p_.rest[std::size_t(i)]));
  double d = std::max(h_, std::isfinite(smax) ? s_.spacing_factor * smax : h_);
  // Capped balls need a spacing well below their radius: at most 2/3 of the cap (the organ's own spacing when
  // the cap is 1.5 x its radius), or the re-packed regions thin out cut after cut.
  if (s_.max_radius > 0) d = std::min(d, std::max(h_, s_.max_radius / 1.5));
  return d;
}

// 4. Algorithm 1's candidates: the deepest medial points first; then (our completion) the middle points by the
//    same rule: where the medial surface's balls leave a part of the group farther than d from every centre (a
//    corner between a cut wall and the organ's surface), a middle point takes a sphere there.
std::vector<std::int32_t> Repacker::packingOrder(const std::vector<std::int32_t>& medial,
                                                 const std::vector<std::int32_t>& pts) const {
  const auto deeper = [&](std::int32_t a, std::int32_t b) { return depth_[std::size_t(a)] > depth_[std::size_t(b)]; };
  std::vector<std::int32_t> order = medial, middle;
  std::stable_sort(order.begin(), order.end(), deeper);
  for (std::int32_t i : pts)
    if (r_.point_class[std::size_t(i)] == kRepackMiddle) middle.push_back(i);
  std::stable_sort(middle.begin(), middle.end(), deeper);
  order.insert(order.end(), middle.begin(), middle.end());
  return order;
}

// 4. Algorithm 1: a sphere wherever every accepted centre is farther than d.
std::vector<std::int32_t> Repacker::packCentres(const std::vector<std::int32_t>& order, double d) const {
  std::vector<std::int32_t> accepted;
  PointGrid centres = grid(p_.rest, d);
  for (std::int32_t i : order) {
    if (centres.anyWithin(p_.rest[std::size_t(i)], d)) continue;
    centres.insert(i);
    accepted.push_back(i);
  }
  return accepted;
}

// 6. Every point to its nearest centre (its Voronoi cell: the mass stays local); radius = the distance to the
//    nearest boundary point plus half a spacing (Algorithm 1; the boundary points sit half a spacing inside the
//    surface they sample), at least one spacing (a sliver without interior points), grown towards the cell's
//    farthest point so that the balls cover the group, all within max_radius (uncapped, a ball reaching out
//    of the tissue puts points, and mass, outside it when it is cut again, and the next balls grow further).
void Repacker::assignCells(const std::vector<std::int32_t>& pts, const std::vector<std::int32_t>& accepted, double d) {
  const auto radiusAt = [&](std::int32_t i) {
    const double rad = std::max(depth_[std::size_t(i)] + 0.5 * h_, h_);
    return s_.max_radius > 0 ? std::min(rad, s_.max_radius) : rad;
  };
  const std::size_t first = r_.centres.size();
  for (std::int32_t i : accepted) {
    r_.centres.push_back(p_.rest[std::size_t(i)]);
    r_.radii.push_back(radiusAt(i));
    r_.masses.push_back(0.0);
  }
  PointGrid centres = grid(r_.centres, d);
  for (std::size_t k = 0; k < accepted.size(); ++k) centres.insert(std::int32_t(first + k));
  cpu::parallelFor(std::int64_t(pts.size()), [&](std::int64_t k) {
    double dist = 0.0;
    r_.owner[std::size_t(pts[std::size_t(k)])] = centres.nearest(p_.rest[std::size_t(pts[std::size_t(k)])], dist);
  });
  for (std::int32_t i : pts) {
    const std::size_t sphere = std::size_t(r_.owner[std::size_t(i)]);
    r_.masses[sphere] += p_.mass[std::size_t(i)];
    const double reach = norm(p_.rest[std::size_t(i)] - r_.centres[sphere]);
    r_.radii[sphere] = std::max(r_.radii[sphere], s_.max_radius > 0 ? std::min(reach, s_.max_radius) : reach);
  }
}

// Isolated points (components of fewer than kMinGroupPoints, e.g. a fragment cut off a sphere): their mass goes
// to the nearest new sphere whose centre they see (no cut between); with none in sight they become a small
// debris sphere of their own (radius: one spacing, or up to its farthest point).
void Repacker::absorbIsolated(const std::vector<std::int32_t>& pts) {
  for (std::int32_t i : pts) r_.point_class[std::size_t(i)] = kRepackBoundary;
  std::int32_t best = visibleCentre(p_.rest[std::size_t(pts.front())]);
  if (best < 0) {
    Vec3d c;
    double m = 0.0;
    for (std::int32_t i : pts) c += p_.rest[std::size_t(i)] * p_.mass[std::size_t(i)], m += p_.mass[std::size_t(i)];
    best = std::int32_t(r_.centres.size());
    r_.centres.push_back(c * (1.0 / m));
    double rad = h_;
    for (std::int32_t i : pts) rad = std::max(rad, norm(p_.rest[std::size_t(i)] - r_.centres.back()));
    r_.radii.push_back(rad);
    r_.masses.push_back(0.0);
  }
  for (std::int32_t i : pts) {
    r_.owner[std::size_t(i)] = best;
    r_.masses[std::size_t(best)] += p_.mass[std::size_t(i)];
  }
}

// The nearest new sphere whose centre x0 sees across no cut (-1: none).
std::int32_t Repacker::visibleCentre(const Vec3d& x0) const {
  std::int32_t best = -1;
  double bd = std::numeric_limits<double>::infinity();
  for (std::size_t q = 0; q < r_.centres.size(); ++q) {
    const double dq = norm(r_.centres[q] - x0);
    if (!(dq < bd)) continue;
    bool hidden = cut_query_.segmentCrosses(x0, r_.centres[q]);
    for (std::size_t c = 0; c < earlier_queries_.size() && !hidden; ++c)
      hidden = earlier_queries_[c].segmentCrosses(x0, r_.centres[q]);
    if (!hidden) bd = dq, best = std::int32_t(q);
  }
  return best;
}

void Repacker::countClasses() {
  for (std::size_t i = 0; i < n_; ++i) {
    if (isContext(i)) continue;
    r_.boundary += r_.point_class[i] == kRepackBoundary;
    r_.medial += r_.point_class[i] == kRepackMedial;
    r_.middle += r_.point_class[i] == kRepackMiddle;
  }
}

}  // namespace

RepackResult packNodalPoints(const RepackPoints& p, const SweptSurface& cut, const RepackSettings& s) {
  checkRepackInput(p, s);
  const std::size_t n = p.size();
  RepackResult r;
  r.owner.assign(n, -1);
  r.point_class.assign(n, kRepackMiddle);
  if (n == 0) return r;
  const auto groups = components(p.visible, n, p.context);
  Repacker repacker(p, cut, s, r);
  repacker.classifyBoundary();
  repacker.measureDepth();
  std::vector<std::size_t> isolated;  // groups too small to hold a sphere of their own
  r.spacing_min = std::numeric_limits<double>::infinity();
  for (std::size_t g = 0; g < groups.size(); ++g) {
    if (groups[g].size() < kMinGroupPoints)
      isolated.push_back(g);
    else
      repacker.packGroup(groups[g]);
  }
  for (std::size_t g : isolated) repacker.absorbIsolated(groups[g]);
  repacker.countClasses();
  if (!std::isfinite(r.spacing_min)) r.spacing_min = r.spacing_max = 0.0;
  return r;
}

std::size_t appendRepackedSpheres(MetaballModel& spheres, const RepackResult& r,
                                  const std::vector<const SweptSurface*>& cuts) {
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
