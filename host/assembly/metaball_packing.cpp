// Packs a closed mesh with overlapping spheres: grid samples, greedy cover by near-medial balls, radius tightening, report, cache.
#include "host/assembly/metaball_packing.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <numeric>
#include <queue>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "base/parallel.h"
#include "model/input_error.h"
#include "host/assembly/metaball_pack_bvh.h"
#include "host/assembly/metaball_pack_checks.h"

namespace inc {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::uint64_t kFormatVersion = 1;
constexpr char kMagic[8] = {'I', 'N', 'C', 'P', 'A', 'C', 'K', '1'};
constexpr std::int64_t kMaxGridCells = 16'000'000;

void progress(const PackingOptions& o, const char* stage, double f) {
  if (o.progress) o.progress(stage, f);
}

void validateOptions(const PackingOptions& o, const std::string& file) {
  auto bad = [&](const char* key, const std::string& why) { throw InputError(file, std::string("packing.") + key, why); };
  if (o.target_spheres < 1 || o.target_spheres > 1'000'000) bad("target_spheres", "must be in [1, 1000000]");
  if (!(o.stop_coverage > 0.0 && o.stop_coverage <= 1.0)) bad("stop_coverage", "must be in (0, 1]");
  if (o.samples < 1000 || o.samples > 20'000'000) bad("samples", "must be in [1000, 20000000]");
  if (!(o.max_protrusion >= 0.0 && o.max_protrusion <= 0.25)) bad("max_protrusion", "must be in [0, 0.25]");
  if (!(o.density_kg_m3 > 0.0) || !std::isfinite(o.density_kg_m3)) bad("density_kg_m3", "must be positive");
  if (!(o.max_self_intersecting_fraction >= 0.0 && o.max_self_intersecting_fraction <= 0.1))
    bad("max_self_intersecting_fraction", "must be in [0, 0.1]");
}

// Regular sample grid: point (i, j, k) at lo + (i + offset, j + offset, k + offset) h.
struct SampleGrid {
  Vec3d lo;
  double h = 0.0;
  int n[3] = {0, 0, 0};
  std::int64_t cells() const { return std::int64_t(n[0]) * n[1] * n[2]; }
  Vec3d point(std::int64_t id, double offset) const {
    const std::int64_t i = id % n[0], j = (id / n[0]) % n[1], k = id / (std::int64_t(n[0]) * n[1]);
    return lo + Vec3d{(double(i) + offset) * h, (double(j) + offset) * h, (double(k) + offset) * h};
  }
};

// Uniform bucket grid over sphere centres (cell >= 2 r_max), so that every sphere that can contain or overlap
// something near p lies in the 27 cells around p's cell.
class SphereHash {
 public:
  SphereHash(const std::vector<Vec3d>& c, const std::vector<double>& r, double min_cell) : c_(c), r_(r) {
    r_max_ = 0.0;
    for (double x : r) r_max_ = std::max(r_max_, x);
    pack::Aabb box;
    for (const auto& p : c) box.grow(p);
    lo_ = box.lo;
    cs_ = std::max({2.0 * r_max_, min_cell, 1e-300});
    for (int a = 0; a < 3; ++a) n_[a] = std::max(1, int(std::floor((box.hi[a] - box.lo[a]) / cs_)) + 1);
    start_.assign(std::size_t(n_[0]) * n_[1] * n_[2] + 1, 0);
    std::vector<int> cell(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
      cell[i] = cellOf(c[i]);
      ++start_[std::size_t(cell[i]) + 1];
    }
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    items_.resize(c.size());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < c.size(); ++i) items_[std::size_t(fill[std::size_t(cell[i])]++)] = int(i);
  }
  double cell() const { return cs_; }
  double rMax() const { return r_max_; }
  template <typename F>
  void forNear(const Vec3d& p, F&& f) const {
    int q[3];
    for (int a = 0; a < 3; ++a) q[a] = clampIdx(p, a);
    for (int k = std::max(0, q[2] - 1); k <= std::min(n_[2] - 1, q[2] + 1); ++k)
      for (int j = std::max(0, q[1] - 1); j <= std::min(n_[1] - 1, q[1] + 1); ++j)
        for (int i = std::max(0, q[0] - 1); i <= std::min(n_[0] - 1, q[0] + 1); ++i) {
          const std::size_t cidx = std::size_t((k * n_[1] + j) * n_[0] + i);
          for (int m = start_[cidx]; m < start_[cidx + 1]; ++m) f(items_[std::size_t(m)]);
        }
  }
  // Signed distance to the union of spheres, min_i(|p - c_i| - r_i): exact outside the union.
  double unionDistance(const Vec3d& p) const {
    double best = std::numeric_limits<double>::infinity();
    forNear(p, [&](int i) { best = std::min(best, norm(p - c_[std::size_t(i)]) - r_[std::size_t(i)]); });
    // Spheres outside the 27 cells are at least cs from p, so their value is >= cs - r_max.
    if (best <= cs_ - r_max_) return best;
    for (std::size_t i = 0; i < c_.size(); ++i) best = std::min(best, norm(p - c_[i]) - r_[i]);
    return best;
  }
  bool covers(const Vec3d& p) const {
    bool hit = false;
    forNear(p, [&](int i) { hit = hit || norm2(p - c_[std::size_t(i)]) <= r_[std::size_t(i)] * r_[std::size_t(i)]; });
    return hit;
  }

 private:
  int clampIdx(const Vec3d& p, int a) const {
    const double f = std::floor((p[a] - lo_[a]) / cs_);
    return int(std::clamp(f, 0.0, double(n_[a] - 1)));
  }
  int cellOf(const Vec3d& p) const { return (clampIdx(p, 2) * n_[1] + clampIdx(p, 1)) * n_[0] + clampIdx(p, 0); }
  const std::vector<Vec3d>& c_;
  const std::vector<double>& r_;
  Vec3d lo_;
  double cs_ = 0.0, r_max_ = 0.0;
  int n_[3] = {1, 1, 1};
  std::vector<int> start_, items_;
};

struct UnionFind {
  std::vector<int> p;
  explicit UnionFind(int n) : p(std::size_t(n)) { std::iota(p.begin(), p.end(), 0); }
  int find(int x) {
    while (p[std::size_t(x)] != x) x = p[std::size_t(x)] = p[std::size_t(p[std::size_t(x)])];
    return x;
  }
  void join(int a, int b) { p[std::size_t(find(a))] = find(b); }
};

// Points on the unit sphere (Fibonacci spiral), deterministic.
std::vector<Vec3d> fibonacciSphere(int n) {
  std::vector<Vec3d> out(static_cast<std::size_t>(n));
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, s = std::sqrt(std::max(0.0, 1.0 - z * z));
    out[std::size_t(i)] = {s * std::cos(golden * i), s * std::sin(golden * i), z};
  }
  return out;
}

struct Fnv {
  std::uint64_t h = 1469598103934665603ULL;
  void bytes(const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ULL;
  }
  template <typename T>
  void value(const T& v) { bytes(&v, sizeof(T)); }
};

}  // namespace

std::uint64_t packCacheKey(const TriangleMesh& mesh, const PackingOptions& o) {
  Fnv f;
  f.value(kFormatVersion);
  f.value(std::uint64_t(mesh.vertices.size()));
  for (const auto& v : mesh.vertices) { f.value(v.x); f.value(v.y); f.value(v.z); }
  f.value(std::uint64_t(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) { f.value(t[0]); f.value(t[1]); f.value(t[2]); }
  f.value(o.target_spheres);
  f.value(o.stop_coverage);
  f.value(o.samples);
  f.value(o.max_protrusion);
  f.value(o.density_kg_m3);
  f.value(o.max_self_intersecting_fraction);
  return f.h;
}

PackedOrgan packOrgan(const TriangleMesh& input, const PackingOptions& opt, const std::string& file) {
  const auto t0 = std::chrono::steady_clock::now();
  validateOptions(opt, file);
  TriangleMesh mesh = input;
  const PackInputReport in = preparePackInput(mesh, file, "mesh", opt.max_self_intersecting_fraction);
  progress(opt, "checked mesh", 1.0);
  const pack::SurfaceDistance surface(mesh);
  const pack::Aabb bbox = surface.bvh().bounds();
  const double diag = norm(bbox.extent());
  const double protrusion = opt.max_protrusion * diag;

  // 1. Sample grid: spacing from the enclosed volume so that about `samples` points fall inside.
  SampleGrid grid;
  grid.h = std::cbrt(in.volume / double(opt.samples));
  for (;;) {
    grid.lo = bbox.lo - Vec3d{grid.h, grid.h, grid.h};
    for (int a = 0; a < 3; ++a) grid.n[a] = int(std::ceil(bbox.extent()[a] / grid.h)) + 2;
    if (grid.cells() <= kMaxGridCells) break;
    grid.h *= 1.25;  // a thin shape in a large box: fewer interior samples rather than unbounded memory
  }
  const std::int64_t cells = grid.cells();
  // Inside by ray parity; depth = unsigned distance to the nearest surface point.
  std::vector<double> depth(std::size_t(cells), -1.0);
  cpu::parallelFor(cells, [&](std::int64_t id) {
    const Vec3d p = grid.point(id, 0.5);
    if (surface.insideByRays(p)) depth[std::size_t(id)] = std::sqrt(surface.bvh().nearest(p).distance2);
  });
  progress(opt, "sampled interior", 1.0);
  std::vector<int> sample_of(std::size_t(cells), -1);
  std::vector<std::int64_t> cell_of;
  std::vector<double> D;
  for (std::int64_t id = 0; id < cells; ++id)
    if (depth[std::size_t(id)] >= 0.0) {
      sample_of[std::size_t(id)] = int(cell_of.size());
      cell_of.push_back(id);
      D.push_back(depth[std::size_t(id)]);
    }
  std::vector<double>().swap(depth);
  const int S = int(cell_of.size());
  if (S < 8)
    throw InputError(file, "mesh", "the surface encloses fewer than 8 grid samples (spacing " +
                                       std::to_string(grid.h) + "); it is too thin to pack at this resolution (raise packing.samples)");

  // Calls f(sample) for every interior sample within distance r of the sample grid point of sample s.
  auto forBall = [&](int s, double r, auto&& f) {
    const std::int64_t id = cell_of[std::size_t(s)];
    const int ci = int(id % grid.n[0]), cj = int((id / grid.n[0]) % grid.n[1]),
              ck = int(id / (std::int64_t(grid.n[0]) * grid.n[1]));
    const int m = int(std::floor(r / grid.h));
    const double r2 = (r / grid.h) * (r / grid.h);
    for (int k = std::max(0, ck - m); k <= std::min(grid.n[2] - 1, ck + m); ++k)
      for (int j = std::max(0, cj - m); j <= std::min(grid.n[1] - 1, cj + m); ++j)
        for (int i = std::max(0, ci - m); i <= std::min(grid.n[0] - 1, ci + m); ++i) {
          const double di = i - ci, dj = j - cj, dk = k - ck;
          if (di * di + dj * dj + dk * dk > r2) continue;
          const int t = sample_of[std::size_t((std::int64_t(k) * grid.n[1] + j) * grid.n[0] + i)];
          if (t >= 0) f(t);
        }
  };

  // 2. Greedy cover (lazy evaluation): every interior sample c is a candidate ball of radius
  // min(D(c) + protrusion, R) (D: distance to the surface). The ball covering the most uncovered samples is
  // taken first; ties go to the lower sample index. Without the cap R the winners are the centres of maximal
  // inscribed balls, i.e. points of the medial axis, large ones first; the cap R makes the organ a set of
  // similar-sized spheres (the medial balls of thin parts stay smaller), and is tuned to the target count.
  struct Cover {
    std::vector<int> chosen;
    std::vector<double> radius;
    std::int64_t covered = 0;
  };
  const std::int64_t stop_count = std::int64_t(std::ceil(opt.stop_coverage * S));
  auto ballRadius = [&](int s, double cap) { return std::min(D[std::size_t(s)] + protrusion, cap); };
  // A ball counts a sample as covered only with this margin to spare, so that the space between samples is
  // covered too and not only the samples (without it the union keeps small voids between the balls).
  const double margin = 0.5 * grid.h;
  auto coverRadius = [&](double r) { return std::max(0.0, r - margin); };
  auto runCover = [&](double cap, int max_count) {
    Cover cv;
    using Entry = std::pair<std::int64_t, int>;  // (gain bound, -sample)
    // Capped balls (deep inside) are all alike: candidates among them on a lattice of stride ~cap / 3h suffice
    // and keep the lazy evaluation cheap; uncapped (medial, near-surface) candidates are all kept.
    const int stride = std::max(1, int(cap / (3.0 * grid.h)));
    std::vector<Entry> init;
    init.reserve(static_cast<std::size_t>(S));
    for (int s = 0; s < S; ++s) {
      if (stride > 1 && D[std::size_t(s)] + protrusion >= cap) {
        const std::int64_t id = cell_of[std::size_t(s)];
        const std::int64_t i = id % grid.n[0], j = (id / grid.n[0]) % grid.n[1], k = id / (std::int64_t(grid.n[0]) * grid.n[1]);
        if (i % stride || j % stride || k % stride) continue;
      }
      const double rr = ballRadius(s, cap) / grid.h + 0.8660254037844386;
      init.push_back({std::int64_t(std::ceil(4.0 / 3.0 * kPi * rr * rr * rr)) + 1, -s});
    }
    std::priority_queue<Entry> heap(std::less<Entry>(), std::move(init));
    std::vector<unsigned char> covered(std::size_t(S), 0);
    while (!heap.empty() && int(cv.chosen.size()) < max_count && cv.covered < stop_count) {
      const auto [bound, neg] = heap.top();
      heap.pop();
      const int s = -neg;
      const double r = ballRadius(s, cap);
      std::int64_t gain = 0;
      forBall(s, coverRadius(r), [&](int t) { gain += covered[std::size_t(t)] ? 0 : 1; });
      if (gain == 0) continue;
      if (!heap.empty() && Entry{gain, neg} < heap.top()) {
        heap.push({gain, neg});  // gains only shrink, so the fresh value is still an upper bound
        continue;
      }
      forBall(s, coverRadius(r), [&](int t) { covered[std::size_t(t)] = 1; });
      cv.covered += gain;
      cv.chosen.push_back(s);
      cv.radius.push_back(r);
    }
    return cv;
  };
  // Tune the cap: N(R) falls with R; start from the volume per sphere with an overlap factor of 3 and correct
  // by (N / target)^(1/3). Keep the smallest cap whose full cover needs at most target_spheres.
  const int target = opt.target_spheres;
  double cap = std::cbrt(3.0 * 3.0 * in.volume / (4.0 * kPi * target));
  // A full cover with up to 10% more spheres than the target is acceptable: it is cut to the target, dropping the
  // last (least useful, the greedy order) spheres. Among acceptable runs the one nearest the target wins.
  Cover best;
  bool have_best = false;
  int best_score = -1;
  double too_small = 0.0;                                     // largest cap known to need too many spheres
  double fits = std::numeric_limits<double>::infinity();       // smallest cap known to fit the target
  const double cap_max = protrusion + *std::max_element(D.begin(), D.end());  // beyond this the cap never binds
  double largest_full_cap = 0.0;
  const int accept = target + std::max(1, target / 10);
  for (int it = 0; it < 8; ++it) {
    Cover cv = runCover(cap, 2 * target);
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
    if (full && n <= target) fits = cap; else too_small = cap;
    double next = cap * std::clamp(std::cbrt(full ? double(std::max(n, 1)) / target : 2.5), 0.6, 1.6);
    if (!(next > too_small && next < fits))
      next = std::isfinite(fits) ? std::sqrt(std::max(too_small, 1e-3 * fits) * fits) : 1.6 * cap;
    if (std::isfinite(fits) && fits - too_small < 0.01 * fits) break;  // bracket closed
    cap = next;
  }
  if (!have_best)  // nothing acceptable: the largest cap that covered everything (or the last), cut at the target
    best = runCover(largest_full_cap > 0.0 ? largest_full_cap : cap, target);
  if (int(best.chosen.size()) > target) {
    best.chosen.resize(std::size_t(target));
    best.radius.resize(std::size_t(target));
  }
  std::vector<int> chosen = std::move(best.chosen);
  const int N = int(chosen.size());

  // 3. Radius tightening (the boundary-matching step; replaces the paper's electrostatic attraction, see
  // docs/packing.md): each sphere shrinks to the smallest radius >= its inscribed radius D that still covers
  // the samples no other sphere covers, so protrusion survives only where it buys coverage.
  std::vector<int> count(std::size_t(S), 0);
  std::vector<double> radius = std::move(best.radius);
  for (int i = 0; i < N; ++i) {
    forBall(chosen[std::size_t(i)], coverRadius(radius[std::size_t(i)]), [&](int t) { ++count[std::size_t(t)]; });
  }
  std::vector<Vec3d> centre(static_cast<std::size_t>(N));
  for (int i = 0; i < N; ++i) centre[std::size_t(i)] = grid.point(cell_of[std::size_t(chosen[std::size_t(i)])], 0.5);
  for (int i = 0; i < N; ++i) {
    const int s = chosen[std::size_t(i)];
    const Vec3d c = centre[std::size_t(i)];
    double need = std::min(D[std::size_t(s)], radius[std::size_t(i)]);
    forBall(s, coverRadius(radius[std::size_t(i)]), [&](int t) {
      if (count[std::size_t(t)] == 1) need = std::max(need, norm(grid.point(cell_of[std::size_t(t)], 0.5) - c));
    });
    const double r_new = std::min(radius[std::size_t(i)], need + margin);
    forBall(s, coverRadius(radius[std::size_t(i)]), [&](int t) {
      if (norm(grid.point(cell_of[std::size_t(t)], 0.5) - c) > coverRadius(r_new)) --count[std::size_t(t)];
    });
    radius[std::size_t(i)] = r_new;
  }
  progress(opt, "tightened radii", 1.0);

  // 3b. Connectivity: a sphere group detached from the rest by a narrow gap (a thin part, a corner) is joined by
  // growing its sphere nearest to another group until they overlap by 5% of the smaller radius (`bridged`).
  int bridged = 0;
  for (;;) {
    UnionFind g(N);
    for (int i = 0; i < N; ++i)
      for (int j = i + 1; j < N; ++j)
        if (norm(centre[std::size_t(i)] - centre[std::size_t(j)]) < radius[std::size_t(i)] + radius[std::size_t(j)]) g.join(i, j);
    const int root0 = g.find(0);
    int bi = -1, bj = -1;
    double gap = std::numeric_limits<double>::infinity();
    for (int i = 0; i < N; ++i) {
      if (g.find(i) == root0) continue;  // grow the group not holding sphere 0 towards any other group
      for (int j = 0; j < N; ++j) {
        if (g.find(j) == g.find(i)) continue;
        const double d = norm(centre[std::size_t(i)] - centre[std::size_t(j)]) - radius[std::size_t(i)] - radius[std::size_t(j)];
        if (d < gap) { gap = d; bi = i; bj = j; }
      }
    }
    // Only a narrow gap (a sampling artefact) is bridged; separate shells of the mesh stay separate groups.
    if (bi < 0 || gap > std::max(2.0 * grid.h, protrusion)) break;
    radius[std::size_t(bi)] += gap + 0.05 * std::min(radius[std::size_t(bi)], radius[std::size_t(bj)]);
    ++bridged;
  }

  PackedOrgan out;
  MetaballModel& mb = out.model;
  mb.rest_centers = centre;
  mb.rest_radii = radius;
  const SphereHash hash(centre, radius, diag / 64.0);

  // 4. Links: overlapping pairs (i < j), sorted.
  UnionFind uf(N);
  double overlap_sum = 0.0;
  for (int i = 0; i < N; ++i) {
    std::vector<int> js;
    hash.forNear(centre[std::size_t(i)], [&](int j) {
      if (j > i && norm(centre[std::size_t(i)] - centre[std::size_t(j)]) < radius[std::size_t(i)] + radius[std::size_t(j)])
        js.push_back(j);
    });
    std::sort(js.begin(), js.end());
    for (int j : js) {
      const double d = norm(centre[std::size_t(i)] - centre[std::size_t(j)]);
      mb.links.push_back({i, j});
      mb.link_rest_lengths.push_back(d);
      overlap_sum += (radius[std::size_t(i)] + radius[std::size_t(j)] - d) /
                     std::min(radius[std::size_t(i)], radius[std::size_t(j)]);
      uf.join(i, j);
    }
  }

  // 5. Masses: each interior sample belongs to the sphere of least power |x - c|^2 - r^2 among those covering it
  // (the power cell), else to the sphere whose surface is nearest; mass = density * volume * share.
  std::vector<int> owner(std::size_t(S), -1);
  cpu::parallelFor(S, [&](std::int64_t s) {
    const Vec3d p = grid.point(cell_of[std::size_t(s)], 0.5);
    double best = std::numeric_limits<double>::infinity();
    int who = -1;
    hash.forNear(p, [&](int i) {
      const double pw = norm2(p - centre[std::size_t(i)]) - radius[std::size_t(i)] * radius[std::size_t(i)];
      if (pw <= 0.0 && (pw < best || (pw == best && i < who))) { best = pw; who = i; }
    });
    if (who < 0)
      for (int i = 0; i < N; ++i) {
        const double d = norm(p - centre[std::size_t(i)]) - radius[std::size_t(i)];
        if (d < best) { best = d; who = i; }
      }
    owner[std::size_t(s)] = who;
  });
  std::vector<double> share(std::size_t(N), 0.5);  // floor of half a sample: no massless sphere
  for (int s = 0; s < S; ++s) share[std::size_t(owner[std::size_t(s)])] += 1.0;
  const double share_total = std::accumulate(share.begin(), share.end(), 0.0);
  mb.masses.resize(std::size_t(N));
  for (int i = 0; i < N; ++i) mb.masses[std::size_t(i)] = opt.density_kg_m3 * in.volume * share[std::size_t(i)] / share_total;
  progress(opt, "linked and weighed", 1.0);

  // 6. Report. Coverage on the grid staggered by h/2 (points the greedy cover never saw).
  PackReport& rep = out.report;
  rep.spheres = N;
  rep.links = int(mb.links.size());
  {
    std::vector<int> roots(static_cast<std::size_t>(N));
    for (int i = 0; i < N; ++i) roots[std::size_t(i)] = uf.find(i);
    std::sort(roots.begin(), roots.end());
    rep.components = int(std::unique(roots.begin(), roots.end()) - roots.begin());
  }
  rep.mesh_volume = in.volume;
  rep.sample_spacing = grid.h;
  rep.mean_overlap = mb.links.empty() ? 0.0 : overlap_sum / double(mb.links.size());
  rep.mean_degree = N ? 2.0 * double(mb.links.size()) / N : 0.0;
  rep.repairs = in.repairs;
  rep.bridged = bridged;
  {
    std::vector<unsigned char> inside(std::size_t(cells), 0);
    cpu::parallelFor(cells, [&](std::int64_t id) {
      const Vec3d p = grid.point(id, 0.0);
      if (surface.insideByRays(p)) inside[std::size_t(id)] = hash.covers(p) ? 2 : 1;
    });
    std::int64_t in_count = 0, cov = 0;
    for (unsigned char v : inside) { in_count += v > 0; cov += v == 2; }
    rep.coverage = in_count ? double(cov) / double(in_count) : 0.0;
  }
  progress(opt, "measured coverage", 1.0);
  {
    const auto& V = mesh.vertices;
    const auto& F = mesh.triangles;
    std::vector<Vec3d> pts(V.begin(), V.end());
    for (const auto& t : F)
      pts.push_back((V[std::size_t(t[0])] + V[std::size_t(t[1])] + V[std::size_t(t[2])]) * (1.0 / 3.0));
    std::vector<double> dev(pts.size());
    cpu::parallelFor(std::int64_t(pts.size()), [&](std::int64_t i) { dev[std::size_t(i)] = std::fabs(hash.unionDistance(pts[std::size_t(i)])); });
    double sum = 0.0, mx = 0.0;
    for (double d : dev) { sum += d; mx = std::max(mx, d); }
    rep.surface_mean = sum / double(dev.size());
    rep.surface_max = mx;
  }
  {
    const auto dirs = fibonacciSphere(32);
    std::vector<double> dev(std::size_t(N) * dirs.size(), -1.0);
    cpu::parallelFor(std::int64_t(dev.size()), [&](std::int64_t k) {
      const std::size_t i = std::size_t(k) / dirs.size();
      const Vec3d q = centre[i] + dirs[std::size_t(k) % dirs.size()] * radius[i];
      bool buried = false;
      hash.forNear(q, [&](int j) {
        buried = buried || (std::size_t(j) != i && norm(q - centre[std::size_t(j)]) < radius[std::size_t(j)] * (1.0 - 1e-9));
      });
      if (!buried) dev[std::size_t(k)] = std::sqrt(surface.bvh().nearest(q).distance2);
    });
    double sum = 0.0, mx = 0.0;
    std::int64_t n = 0;
    for (double d : dev)
      if (d >= 0.0) { sum += d; mx = std::max(mx, d); ++n; }
    rep.union_mean = n ? sum / double(n) : 0.0;
    rep.union_max = mx;
    double prot = -std::numeric_limits<double>::infinity();
    for (int i = 0; i < N; ++i)
      prot = std::max(prot, radius[std::size_t(i)] - D[std::size_t(chosen[std::size_t(i)])]);
    rep.max_protrusion = prot;
  }
  rep.key = packCacheKey(input, opt);
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress(opt, "done", 1.0);
  return out;
}

namespace {

template <typename T>
void put(std::ostream& s, const T& v) { s.write(reinterpret_cast<const char*>(&v), sizeof(T)); }
template <typename T>
bool get(std::istream& s, T& v) { return bool(s.read(reinterpret_cast<char*>(&v), sizeof(T))); }

void writePack(const std::string& path, const PackedOrgan& p) {
  std::ofstream s(path, std::ios::binary | std::ios::trunc);
  if (!s) throw InputError(path, "", "cannot write the sphere-pack cache");
  s.write(kMagic, sizeof(kMagic));
  const auto& m = p.model;
  const auto& r = p.report;
  put(s, r.key);
  put(s, std::uint64_t(m.size()));
  for (std::size_t i = 0; i < m.size(); ++i) {
    put(s, m.rest_centers[i].x); put(s, m.rest_centers[i].y); put(s, m.rest_centers[i].z);
    put(s, m.rest_radii[i]); put(s, m.masses[i]);
  }
  put(s, std::uint64_t(m.links.size()));
  for (std::size_t i = 0; i < m.links.size(); ++i) {
    put(s, m.links[i][0]); put(s, m.links[i][1]); put(s, m.link_rest_lengths[i]);
  }
  put(s, r.components);
  for (double v : {r.mesh_volume, r.sample_spacing, r.coverage, r.surface_mean, r.surface_max, r.union_mean,
                   r.union_max, r.max_protrusion, r.mean_overlap, r.mean_degree})
    put(s, v);
  put(s, std::uint64_t(r.repairs.size()));
  s.write(r.repairs.data(), std::streamsize(r.repairs.size()));
  put(s, r.key);  // trailer: a truncated file fails here
  if (!s) throw InputError(path, "", "failed writing the sphere-pack cache");
}

// Returns false for a missing, foreign, stale or corrupt file.
bool readPack(const std::string& path, std::uint64_t key, PackedOrgan& p) {
  std::ifstream s(path, std::ios::binary);
  if (!s) return false;
  char magic[8];
  if (!s.read(magic, sizeof(magic)) || std::memcmp(magic, kMagic, sizeof(magic)) != 0) return false;
  std::uint64_t k = 0, n = 0, l = 0, rs = 0;
  if (!get(s, k) || k != key || !get(s, n) || n > 10'000'000) return false;
  auto& m = p.model;
  m = MetaballModel{};
  m.rest_centers.resize(n);
  m.rest_radii.resize(n);
  m.masses.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Vec3d& c = m.rest_centers[i];
    if (!get(s, c.x) || !get(s, c.y) || !get(s, c.z) || !get(s, m.rest_radii[i]) || !get(s, m.masses[i])) return false;
    if (!isFinite(c) || !(m.rest_radii[i] > 0.0) || !(m.masses[i] > 0.0)) return false;
  }
  if (!get(s, l) || l > 100'000'000) return false;
  m.links.resize(l);
  m.link_rest_lengths.resize(l);
  for (std::size_t i = 0; i < l; ++i) {
    if (!get(s, m.links[i][0]) || !get(s, m.links[i][1]) || !get(s, m.link_rest_lengths[i])) return false;
    if (m.links[i][0] < 0 || m.links[i][0] >= m.links[i][1] || std::uint64_t(m.links[i][1]) >= n) return false;
  }
  auto& r = p.report;
  r = PackReport{};
  if (!get(s, r.components)) return false;
  for (double* v : {&r.mesh_volume, &r.sample_spacing, &r.coverage, &r.surface_mean, &r.surface_max, &r.union_mean,
                    &r.union_max, &r.max_protrusion, &r.mean_overlap, &r.mean_degree})
    if (!get(s, *v)) return false;
  if (!get(s, rs) || rs > 4096) return false;
  r.repairs.resize(rs);
  if (rs && !s.read(r.repairs.data(), std::streamsize(rs))) return false;
  std::uint64_t trailer = 0;
  if (!get(s, trailer) || trailer != key) return false;
  r.spheres = int(n);
  r.links = int(l);
  r.mean_degree = n ? 2.0 * double(l) / double(n) : 0.0;
  r.key = key;
  r.from_cache = true;
  return true;
}

}  // namespace

PackedOrgan loadOrBuildPack(const TriangleMesh& mesh, const PackingOptions& options, const std::string& cache_path,
                            const std::string& file) {
  validateOptions(options, file);
  const std::uint64_t key = packCacheKey(mesh, options);
  PackedOrgan p;
  if (readPack(cache_path, key, p)) return p;
  p = packOrgan(mesh, options, file);
  writePack(cache_path, p);
  return p;
}

std::string defaultPackCachePath(const std::string& mesh_path) { return mesh_path + ".pack"; }

std::string describePack(const PackReport& r) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "%d spheres, %d links (%d component%s%s), coverage %.2f%%, surface->union mean %.3g max %.3g, "
                "union->surface mean %.3g max %.3g, protrusion %.3g (mesh units), %s",
                r.spheres, r.links, r.components, r.components == 1 ? "" : "s",
                r.bridged ? (", " + std::to_string(r.bridged) + " bridged").c_str() : "", 100.0 * r.coverage,
                r.surface_mean, r.surface_max, r.union_mean, r.union_max, r.max_protrusion,
                r.from_cache ? "from cache" : (std::to_string(r.seconds).substr(0, 5) + " s").c_str());
  std::string s = buf;
  if (!r.repairs.empty()) s += "; input: " + r.repairs;
  return s;
}

}  // namespace inc
