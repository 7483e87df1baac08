// Packs a closed mesh with overlapping spheres: the phases in order (placement in metaball_pack_cover), links, masses,
// report, cache.
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
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "base/parallel.h"
#include "host/assembly/metaball_pack_checks.h"
#include "host/assembly/metaball_pack_cover.h"
#include "host/assembly/sphere_graph_repair.h"
#include "host/io/triangle_bvh.h"
#include "model/input_error.h"

namespace inc {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::uint64_t kFormatVersion = 2;  // 2: stragglers linked or dropped, their counts in the report
// Widest gap between two balls, in mean sphere radii, that a link joining a straggler group may cross.
constexpr double kStragglerReach = 2.0;
constexpr char kMagic[8] = {'I', 'N', 'C', 'P', 'A', 'C', 'K', '1'};

void progress(const PackingOptions& o, const char* stage, double f) {
  if (o.progress) o.progress(stage, f);
}

void validateOptions(const PackingOptions& o, const std::string& file) {
  auto bad = [&](const char* key, const std::string& why) {
    throw InputError(file, std::string("packing.") + key, why);
  };
  if (o.target_spheres < 1 || o.target_spheres > 1'000'000) bad("target_spheres", "must be in [1, 1000000]");
  if (!(o.stop_coverage > 0.0 && o.stop_coverage <= 1.0)) bad("stop_coverage", "must be in (0, 1]");
  if (o.samples < 1000 || o.samples > 20'000'000) bad("samples", "must be in [1000, 20000000]");
  if (!(o.max_protrusion >= 0.0 && o.max_protrusion <= 0.25)) bad("max_protrusion", "must be in [0, 0.25]");
  if (!(o.density_kg_m3 > 0.0) || !std::isfinite(o.density_kg_m3)) bad("density_kg_m3", "must be positive");
  if (!(o.max_self_intersecting_fraction >= 0.0 && o.max_self_intersecting_fraction <= 0.1))
    bad("max_self_intersecting_fraction", "must be in [0, 0.1]");
}

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

double meanRadius(const std::vector<double>& radius) {
  return radius.empty() ? 0.0 : std::accumulate(radius.begin(), radius.end(), 0.0) / double(radius.size());
}

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
  void value(const T& v) {
    bytes(&v, sizeof(T));
  }
};

}  // namespace

std::uint64_t packCacheKey(const TriangleMesh& mesh, const PackingOptions& o) {
  Fnv f;
  f.value(kFormatVersion);
  f.value(std::uint64_t(mesh.vertices.size()));
  for (const auto& v : mesh.vertices) {
    f.value(v.x);
    f.value(v.y);
    f.value(v.z);
  }
  f.value(std::uint64_t(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    f.value(t[0]);
    f.value(t[1]);
    f.value(t[2]);
  }
  f.value(o.target_spheres);
  f.value(o.stop_coverage);
  f.value(o.samples);
  f.value(o.max_protrusion);
  f.value(o.density_kg_m3);
  f.value(o.max_self_intersecting_fraction);
  return f.h;
}

namespace {

// Figures the report takes from the links.
struct LinkFigures {
  double mean_overlap = 0.0;  // mean over links of (r_i + r_j - d_ij) / min(r_i, r_j)
  int components = 0;         // connected components of the overlap graph
};

// Links: overlapping pairs (i < j), sorted, with their rest lengths.
LinkFigures linkOverlappingSpheres(MetaballModel& mb, const SphereHash& hash) {
  const std::vector<Vec3d>& centre = mb.rest_centers;
  const std::vector<double>& radius = mb.rest_radii;
  const int N = int(centre.size());
  pack::UnionFind uf(N);
  double overlap_sum = 0.0;
  for (int i = 0; i < N; ++i) {
    std::vector<int> js;
    hash.forNear(centre[std::size_t(i)], [&](int j) {
      if (j > i &&
          norm(centre[std::size_t(i)] - centre[std::size_t(j)]) < radius[std::size_t(i)] + radius[std::size_t(j)])
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
  LinkFigures fig;
  fig.mean_overlap = mb.links.empty() ? 0.0 : overlap_sum / double(mb.links.size());
  std::vector<int> roots(static_cast<std::size_t>(N));
  for (int i = 0; i < N; ++i) roots[std::size_t(i)] = uf.find(i);
  std::sort(roots.begin(), roots.end());
  fig.components = int(std::unique(roots.begin(), roots.end()) - roots.begin());
  return fig;
}

// Masses: each interior sample belongs to the sphere of least power |x - c|^2 - r^2 among those covering it
// (the power cell), else to the sphere whose surface is nearest; mass = density * volume * share.
void weighSpheres(MetaballModel& mb, const pack::InteriorSamples& samples, const SphereHash& hash, double density,
                  double volume) {
  const std::vector<Vec3d>& centre = mb.rest_centers;
  const std::vector<double>& radius = mb.rest_radii;
  const int N = int(centre.size());
  const int S = samples.count();
  std::vector<int> owner(std::size_t(S), -1);
  cpu::parallelFor(S, [&](std::int64_t s) {
    const Vec3d p = samples.point(int(s));
    double best = std::numeric_limits<double>::infinity();
    int who = -1;
    hash.forNear(p, [&](int i) {
      const double pw = norm2(p - centre[std::size_t(i)]) - radius[std::size_t(i)] * radius[std::size_t(i)];
      if (pw <= 0.0 && (pw < best || (pw == best && i < who))) {
        best = pw;
        who = i;
      }
    });
    if (who < 0)
      for (int i = 0; i < N; ++i) {
        const double d = norm(p - centre[std::size_t(i)]) - radius[std::size_t(i)];
        if (d < best) {
          best = d;
          who = i;
        }
      }
    owner[std::size_t(s)] = who;
  });
  std::vector<double> share(std::size_t(N), 0.5);  // floor of half a sample: no massless sphere
  for (int s = 0; s < S; ++s) share[std::size_t(owner[std::size_t(s)])] += 1.0;
  const double share_total = std::accumulate(share.begin(), share.end(), 0.0);
  mb.masses.resize(std::size_t(N));
  for (int i = 0; i < N; ++i) mb.masses[std::size_t(i)] = density * volume * share[std::size_t(i)] / share_total;
}

// Coverage on the grid staggered by h/2 (points the greedy cover never saw): the fraction of its inside points
// that lie in the sphere union.
double staggeredCoverage(const pack::SampleGrid& grid, const pack::SurfaceDistance& surface, const SphereHash& hash) {
  const std::int64_t cells = grid.cells();
  std::vector<unsigned char> inside(std::size_t(cells), 0);
  cpu::parallelFor(cells, [&](std::int64_t id) {
    const Vec3d p = grid.point(id, 0.0);
    if (surface.insideByRays(p)) inside[std::size_t(id)] = hash.covers(p) ? 2 : 1;
  });
  std::int64_t in_count = 0, cov = 0;
  for (unsigned char v : inside) {
    in_count += v > 0;
    cov += v == 2;
  }
  return in_count ? double(cov) / double(in_count) : 0.0;
}

// Mesh surface -> union boundary: |union distance| at the vertices and triangle centroids.
void measureSurfaceToUnion(const TriangleMesh& mesh, const SphereHash& hash, PackReport& rep) {
  const auto& V = mesh.vertices;
  const auto& F = mesh.triangles;
  std::vector<Vec3d> pts(V.begin(), V.end());
  for (const auto& t : F)
    pts.push_back((V[std::size_t(t[0])] + V[std::size_t(t[1])] + V[std::size_t(t[2])]) * (1.0 / 3.0));
  std::vector<double> dev(pts.size());
  cpu::parallelFor(std::int64_t(pts.size()),
                   [&](std::int64_t i) { dev[std::size_t(i)] = std::fabs(hash.unionDistance(pts[std::size_t(i)])); });
  double sum = 0.0, mx = 0.0;
  for (double d : dev) {
    sum += d;
    mx = std::max(mx, d);
  }
  rep.surface_mean = sum / double(dev.size());
  rep.surface_max = mx;
}

// Union boundary -> mesh surface: distance to the surface of points on the sphere surfaces (32 directions each)
// that no other sphere buries.
void measureUnionToSurface(const MetaballModel& mb, const SphereHash& hash, const pack::SurfaceDistance& surface,
                           PackReport& rep) {
  const std::vector<Vec3d>& centre = mb.rest_centers;
  const std::vector<double>& radius = mb.rest_radii;
  const auto dirs = fibonacciSphere(32);
  std::vector<double> dev(centre.size() * dirs.size(), -1.0);
  cpu::parallelFor(std::int64_t(dev.size()), [&](std::int64_t k) {
    const std::size_t i = std::size_t(k) / dirs.size();
    const Vec3d q = centre[i] + dirs[std::size_t(k) % dirs.size()] * radius[i];
    bool buried = false;
    hash.forNear(q, [&](int j) {
      buried =
          buried || (std::size_t(j) != i && norm(q - centre[std::size_t(j)]) < radius[std::size_t(j)] * (1.0 - 1e-9));
    });
    if (!buried) dev[std::size_t(k)] = std::sqrt(surface.bvh().nearest(q).distance2);
  });
  double sum = 0.0, mx = 0.0;
  std::int64_t n = 0;
  for (double d : dev)
    if (d >= 0.0) {
      sum += d;
      mx = std::max(mx, d);
      ++n;
    }
  rep.union_mean = n ? sum / double(n) : 0.0;
  rep.union_max = mx;
}

// max_i (r_i - D(c_i)): how far a sphere reaches beyond the surface.
double maxProtrusion(const std::vector<double>& radius, const pack::InteriorSamples& samples,
                     const std::vector<int>& chosen) {
  double prot = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < radius.size(); ++i)
    prot = std::max(prot, radius[i] - samples.depth[std::size_t(chosen[i])]);
  return prot;
}

}  // namespace

PackedOrgan packOrgan(const TriangleMesh& input, const PackingOptions& opt, const std::string& file) {
  const auto t0 = std::chrono::steady_clock::now();
  validateOptions(opt, file);
  TriangleMesh mesh = input;
  const PackInputReport in = preparePackInput(mesh, file, opt.mesh_key, opt.max_self_intersecting_fraction);
  progress(opt, "checked mesh", 1.0);
  const pack::SurfaceDistance surface(mesh);
  const pack::Aabb bbox = surface.bvh().bounds();
  const double diag = norm(bbox.extent());
  const double protrusion = opt.max_protrusion * diag;

  // 1. Sample grid: spacing from the enclosed volume so that about `samples` points fall inside.
  const pack::SampleGrid grid = pack::sampleGridFor(bbox, in.volume, opt.samples);
  const pack::InteriorSamples samples = pack::collectSamples(grid, pack::interiorDepth(grid, surface));
  progress(opt, "sampled interior", 1.0);
  if (samples.count() < 8)
    throw InputError(file, opt.mesh_key,
                     "the surface encloses fewer than 8 grid samples (spacing " + std::to_string(grid.h) +
                         "); it is too thin to pack at this resolution (raise packing.samples)");

  // 2. Greedy cover by near-medial balls, its radius cap tuned to the target count.
  const pack::GreedyCover cover(samples, protrusion, opt.stop_coverage);
  pack::SphereCover best = pack::coverNearTarget(cover, in.volume, opt);
  const std::vector<int> chosen = std::move(best.chosen);

  // 3. Radius tightening (the boundary-matching step; replaces the paper's electrostatic attraction, see
  // docs/packing.md): protrusion survives only where it buys coverage.
  std::vector<double> radius = std::move(best.radius);
  std::vector<Vec3d> centre = pack::tightenRadii(cover, chosen, radius);
  progress(opt, "tightened radii", 1.0);

  // 3b. Connectivity: a sphere group detached from the rest by a narrow gap (a thin part, a corner) is joined by
  // growing its sphere nearest to another group until they overlap by 5% of the smaller radius (`bridged`).
  const int bridged = pack::bridgeNarrowGaps(centre, radius, std::max(2.0 * grid.h, protrusion));

  PackedOrgan out;
  MetaballModel& mb = out.model;
  mb.rest_centers = std::move(centre);
  mb.rest_radii = std::move(radius);
  const double protruding = maxProtrusion(mb.rest_radii, samples, chosen);  // before a drop renumbers the spheres

  // 4. Links; groups that a wider gap still separates are linked inside the mesh or dropped (sphere_graph_repair.h),
  // so that every sphere of a piece holds constraints to the rest of it; then 5. masses over the spheres kept.
  const LinkFigures links = linkOverlappingSpheres(mb, SphereHash(mb.rest_centers, mb.rest_radii, diag / 64.0));
  const SphereGraphRepair joined = connectSphereGraph(mb, mesh, kStragglerReach * meanRadius(mb.rest_radii));
  const SphereHash hash(mb.rest_centers, mb.rest_radii, diag / 64.0);
  weighSpheres(mb, samples, hash, opt.density_kg_m3, in.volume);
  progress(opt, "linked and weighed", 1.0);

  // 6. Report.
  PackReport& rep = out.report;
  rep.spheres = int(mb.size());
  rep.links = int(mb.links.size());
  rep.components = joined.components_after;
  rep.stragglers_linked = joined.linked;
  rep.dropped = joined.dropped;
  rep.mesh_volume = in.volume;
  rep.sample_spacing = grid.h;
  rep.mean_overlap = links.mean_overlap;
  rep.mean_degree = mb.size() ? 2.0 * double(mb.links.size()) / double(mb.size()) : 0.0;
  rep.repairs = in.repairs;
  rep.bridged = bridged;
  rep.coverage = staggeredCoverage(grid, surface, hash);
  progress(opt, "measured coverage", 1.0);
  measureSurfaceToUnion(mesh, hash, rep);
  measureUnionToSurface(mb, hash, surface, rep);
  rep.max_protrusion = protruding;
  rep.key = packCacheKey(input, opt);
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress(opt, "done", 1.0);
  return out;
}

namespace {

template <typename T>
void put(std::ostream& s, const T& v) {
  s.write(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <typename T>
bool get(std::istream& s, T& v) {
  return bool(s.read(reinterpret_cast<char*>(&v), sizeof(T)));
}

void writePack(const std::string& path, const PackedOrgan& p) {
  std::ofstream s(path, std::ios::binary | std::ios::trunc);
  if (!s) throw InputError(path, "", "cannot write the sphere-pack cache");
  s.write(kMagic, sizeof(kMagic));
  const auto& m = p.model;
  const auto& r = p.report;
  put(s, r.key);
  put(s, std::uint64_t(m.size()));
  for (std::size_t i = 0; i < m.size(); ++i) {
    put(s, m.rest_centers[i].x);
    put(s, m.rest_centers[i].y);
    put(s, m.rest_centers[i].z);
    put(s, m.rest_radii[i]);
    put(s, m.masses[i]);
  }
  put(s, std::uint64_t(m.links.size()));
  for (std::size_t i = 0; i < m.links.size(); ++i) {
    put(s, m.links[i][0]);
    put(s, m.links[i][1]);
    put(s, m.link_rest_lengths[i]);
  }
  put(s, r.components);
  put(s, r.stragglers_linked);
  put(s, r.dropped);
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
  if (!get(s, r.components) || !get(s, r.stragglers_linked) || !get(s, r.dropped)) return false;
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
  if (r.stragglers_linked > 0 || r.dropped > 0)
    s += "; " + std::to_string(r.stragglers_linked) + " straggler" + (r.stragglers_linked == 1 ? "" : "s") +
         " linked, " + std::to_string(r.dropped) + " dropped";
  if (!r.repairs.empty()) s += "; input: " + r.repairs;
  return s;
}

}  // namespace inc
