// Sphere placement for the packer: interior sample grid, greedy cover by near-medial balls, radius tightening,
// bridging.
#include "host/assembly/metaball_pack_cover.h"

#include <functional>
#include <limits>
#include <queue>
#include <utility>

#include "base/parallel.h"

namespace inc::pack {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::int64_t kMaxGridCells = 16'000'000;

void progress(const PackingOptions& o, const char* stage, double f) {
  if (o.progress) o.progress(stage, f);
}

}  // namespace

SampleGrid sampleGridFor(const Aabb& bbox, double volume, int samples) {
  SampleGrid grid;
  grid.h = std::cbrt(volume / double(samples));
  for (;;) {
    grid.lo = bbox.lo - Vec3d{grid.h, grid.h, grid.h};
    for (int a = 0; a < 3; ++a) grid.n[a] = int(std::ceil(bbox.extent()[a] / grid.h)) + 2;
    if (grid.cells() <= kMaxGridCells) break;
    grid.h *= 1.25;  // a thin shape in a large box: fewer interior samples rather than unbounded memory
  }
  return grid;
}

std::vector<double> interiorDepth(const SampleGrid& grid, const SurfaceDistance& surface) {
  const std::int64_t cells = grid.cells();
  // Inside by ray parity; depth = unsigned distance to the nearest surface point.
  std::vector<double> depth(std::size_t(cells), -1.0);
  cpu::parallelFor(cells, [&](std::int64_t id) {
    const Vec3d p = grid.point(id, 0.5);
    if (surface.insideByRays(p)) depth[std::size_t(id)] = std::sqrt(surface.bvh().nearest(p).distance2);
  });
  return depth;
}

InteriorSamples collectSamples(const SampleGrid& grid, const std::vector<double>& depth) {
  InteriorSamples s;
  s.grid = grid;
  const std::int64_t cells = grid.cells();
  s.sample_of.assign(std::size_t(cells), -1);
  for (std::int64_t id = 0; id < cells; ++id)
    if (depth[std::size_t(id)] >= 0.0) {
      s.sample_of[std::size_t(id)] = int(s.cell_of.size());
      s.cell_of.push_back(id);
      s.depth.push_back(depth[std::size_t(id)]);
    }
  return s;
}

GreedyCover::GreedyCover(const InteriorSamples& samples, double protrusion, double stop_coverage)
    : samples_(samples),
      protrusion_(protrusion),
      stop_count_(std::int64_t(std::ceil(stop_coverage * samples.count()))) {}

SphereCover GreedyCover::run(double cap, int max_count) const {
  const SampleGrid& grid = samples_.grid;
  const std::vector<double>& D = samples_.depth;
  const int S = samples_.count();
  SphereCover cv;
  using Entry = std::pair<std::int64_t, int>;  // (gain bound, -sample)
  // Capped balls (deep inside) are all alike: candidates among them on a lattice of stride ~cap / 3h suffice
  // and keep the lazy evaluation cheap; uncapped (medial, near-surface) candidates are all kept.
  const int stride = std::max(1, int(cap / (3.0 * grid.h)));
  std::vector<Entry> init;
  init.reserve(static_cast<std::size_t>(S));
  for (int s = 0; s < S; ++s) {
    if (stride > 1 && D[std::size_t(s)] + protrusion_ >= cap) {
      const std::int64_t id = samples_.cell_of[std::size_t(s)];
      const std::int64_t i = id % grid.n[0], j = (id / grid.n[0]) % grid.n[1],
                         k = id / (std::int64_t(grid.n[0]) * grid.n[1]);
      if (i % stride || j % stride || k % stride) continue;
    }
    const double rr = ballRadius(s, cap) / grid.h + 0.8660254037844386;
    init.push_back({std::int64_t(std::ceil(4.0 / 3.0 * kPi * rr * rr * rr)) + 1, -s});
  }
  std::priority_queue<Entry> heap(std::less<Entry>(), std::move(init));
  std::vector<unsigned char> covered(std::size_t(S), 0);
  while (!heap.empty() && int(cv.chosen.size()) < max_count && cv.covered < stop_count_) {
    const auto [bound, neg] = heap.top();
    heap.pop();
    const int s = -neg;
    const double r = ballRadius(s, cap);
    std::int64_t gain = 0;
    samples_.forBall(s, coverRadius(r), [&](int t) { gain += covered[std::size_t(t)] ? 0 : 1; });
    if (gain == 0) continue;
    if (!heap.empty() && Entry{gain, neg} < heap.top()) {
      heap.push({gain, neg});  // gains only shrink, so the fresh value is still an upper bound
      continue;
    }
    samples_.forBall(s, coverRadius(r), [&](int t) { covered[std::size_t(t)] = 1; });
    cv.covered += gain;
    cv.chosen.push_back(s);
    cv.radius.push_back(r);
  }
  return cv;
}

SphereCover coverNearTarget(const GreedyCover& cover, double volume, const PackingOptions& opt) {
  const std::vector<double>& D = cover.samples().depth;
  const double protrusion = cover.protrusion();
  const std::int64_t stop_count = cover.stopCount();
  // Tune the cap: N(R) falls with R; start from the volume per sphere with an overlap factor of 3 and correct
  // by (N / target)^(1/3). Keep the smallest cap whose full cover needs at most target_spheres.
  const int target = opt.target_spheres;
  double cap = std::cbrt(3.0 * 3.0 * volume / (4.0 * kPi * target));
  // A full cover with up to 10% more spheres than the target is acceptable: it is cut to the target, dropping the
  // last (least useful, the greedy order) spheres. Among acceptable runs the one nearest the target wins.
  SphereCover best;
  bool have_best = false;
  int best_score = -1;
  double too_small = 0.0;                                 // largest cap known to need too many spheres
  double fits = std::numeric_limits<double>::infinity();  // smallest cap known to fit the target
  const double cap_max = protrusion + *std::max_element(D.begin(), D.end());  // beyond this the cap never binds
  double largest_full_cap = 0.0;
  const int accept = target + std::max(1, target / 10);
  for (int it = 0; it < 8; ++it) {
    SphereCover cv = cover.run(cap, 2 * target);
    const bool full = cv.covered >= stop_count;
    const int n = int(cv.chosen.size());
    progress(opt, "placing spheres", (it + 1) / 8.0);
    if (full) largest_full_cap = std::max(largest_full_cap, cap);
    if (full && n <= accept) {
      const int score = std::min(n, target) * 2 - (n > target ? 1 : 0);
      if (score > best_score) {
        best_score = score;
        best = std::move(cv);
        have_best = true;
      }
      if (n >= int(0.95 * target) || cap >= cap_max) break;  // close enough, or the cap no longer binds
    }
    if (full && n <= target)
      fits = cap;
    else
      too_small = cap;
    double next = cap * std::clamp(std::cbrt(full ? double(std::max(n, 1)) / target : 2.5), 0.6, 1.6);
    if (!(next > too_small && next < fits))
      next = std::isfinite(fits) ? std::sqrt(std::max(too_small, 1e-3 * fits) * fits) : 1.6 * cap;
    if (std::isfinite(fits) && fits - too_small < 0.01 * fits) break;  // bracket closed
    cap = next;
  }
  if (!have_best)  // nothing acceptable: the largest cap that covered everything (or the last), cut at the target
    best = cover.run(largest_full_cap > 0.0 ? largest_full_cap : cap, target);
  if (int(best.chosen.size()) > target) {
    best.chosen.resize(std::size_t(target));
    best.radius.resize(std::size_t(target));
  }
  return best;
}

std::vector<Vec3d> tightenRadii(const GreedyCover& cover, const std::vector<int>& chosen, std::vector<double>& radius) {
  const InteriorSamples& samples = cover.samples();
  const int N = int(chosen.size());
  // How many spheres cover each sample: a sample covered once pins its sphere's radius.
  std::vector<int> count(std::size_t(samples.count()), 0);
  for (int i = 0; i < N; ++i) {
    samples.forBall(chosen[std::size_t(i)], cover.coverRadius(radius[std::size_t(i)]),
                    [&](int t) { ++count[std::size_t(t)]; });
  }
  std::vector<Vec3d> centre(static_cast<std::size_t>(N));
  for (int i = 0; i < N; ++i) centre[std::size_t(i)] = samples.point(chosen[std::size_t(i)]);
  for (int i = 0; i < N; ++i) {
    const int s = chosen[std::size_t(i)];
    const Vec3d c = centre[std::size_t(i)];
    double need = std::min(samples.depth[std::size_t(s)], radius[std::size_t(i)]);
    samples.forBall(s, cover.coverRadius(radius[std::size_t(i)]), [&](int t) {
      if (count[std::size_t(t)] == 1) need = std::max(need, norm(samples.point(t) - c));
    });
    const double r_new = std::min(radius[std::size_t(i)], need + cover.margin());
    samples.forBall(s, cover.coverRadius(radius[std::size_t(i)]), [&](int t) {
      if (norm(samples.point(t) - c) > cover.coverRadius(r_new)) --count[std::size_t(t)];
    });
    radius[std::size_t(i)] = r_new;
  }
  return centre;
}

int bridgeNarrowGaps(const std::vector<Vec3d>& centre, std::vector<double>& radius, double max_gap) {
  const int N = int(centre.size());
  int bridged = 0;
  for (;;) {
    UnionFind g(N);
    for (int i = 0; i < N; ++i)
      for (int j = i + 1; j < N; ++j)
        if (norm(centre[std::size_t(i)] - centre[std::size_t(j)]) < radius[std::size_t(i)] + radius[std::size_t(j)])
          g.join(i, j);
    const int root0 = g.find(0);
    int bi = -1, bj = -1;
    double gap = std::numeric_limits<double>::infinity();
    for (int i = 0; i < N; ++i) {
      if (g.find(i) == root0) continue;  // grow the group not holding sphere 0 towards any other group
      for (int j = 0; j < N; ++j) {
        if (g.find(j) == g.find(i)) continue;
        const double d =
            norm(centre[std::size_t(i)] - centre[std::size_t(j)]) - radius[std::size_t(i)] - radius[std::size_t(j)];
        if (d < gap) {
          gap = d;
          bi = i;
          bj = j;
        }
      }
    }
    // Only a narrow gap (a sampling artefact) is bridged; separate shells of the mesh stay separate groups.
    if (bi < 0 || gap > max_gap) break;
    radius[std::size_t(bi)] += gap + 0.05 * std::min(radius[std::size_t(bi)], radius[std::size_t(bj)]);
    ++bridged;
  }
  return bridged;
}

}  // namespace inc::pack
