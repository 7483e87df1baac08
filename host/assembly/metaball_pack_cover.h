// Sphere placement for the packer: interior sample grid, greedy cover by near-medial balls, radius tightening,
// bridging.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "host/assembly/metaball_packing.h"
#include "host/io/triangle_bvh.h"
#include "physics/vec3.h"

namespace inc::pack {

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

// The grid points inside the surface (the samples), each with its depth D: the distance to the surface.
struct InteriorSamples {
  SampleGrid grid;
  std::vector<int> sample_of;         // grid cell -> sample index, -1 outside
  std::vector<std::int64_t> cell_of;  // sample -> grid cell
  std::vector<double> depth;          // sample -> D, mesh units

  int count() const { return int(cell_of.size()); }
  Vec3d point(int s) const { return grid.point(cell_of[std::size_t(s)], 0.5); }
  // Calls f(sample) for every interior sample within distance r of the sample grid point of sample s.
  template <typename F>
  void forBall(int s, double r, F&& f) const {
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
  }
};

// Disjoint sets of sphere indices (path halving): the connected groups of overlapping spheres.
struct UnionFind {
  std::vector<int> p;
  explicit UnionFind(int n) : p(std::size_t(n)) { std::iota(p.begin(), p.end(), 0); }
  int find(int x) {
    while (p[std::size_t(x)] != x) x = p[std::size_t(x)] = p[std::size_t(p[std::size_t(x)])];
    return x;
  }
  void join(int a, int b) { p[std::size_t(find(a))] = find(b); }
};

// The grid whose spacing puts about `samples` points inside `volume`, widened while it would exceed the cell cap.
SampleGrid sampleGridFor(const Aabb& bbox, double volume, int samples);

// Depth of every grid cell centre: the distance to the surface inside (by ray parity), -1 outside.
std::vector<double> interiorDepth(const SampleGrid& grid, const SurfaceDistance& surface);

// The inside cells of `depth` as samples, in cell order.
InteriorSamples collectSamples(const SampleGrid& grid, const std::vector<double>& depth);

// Spheres in greedy order (sample index of each centre) with their radii.
struct SphereCover {
  std::vector<int> chosen;
  std::vector<double> radius;
  std::int64_t covered = 0;  // samples covered
};

// Greedy cover (lazy evaluation): every interior sample c is a candidate ball of radius min(D(c) + protrusion, R)
// (D: distance to the surface). The ball covering the most uncovered samples is taken first; ties go to the lower
// sample index. Without the cap R the winners are the centres of maximal inscribed balls, i.e. points of the medial
// axis, large ones first; the cap R makes the organ a set of similar-sized spheres (the medial balls of thin parts
// stay smaller), and is tuned to the target count.
class GreedyCover {
 public:
  GreedyCover(const InteriorSamples& samples, double protrusion, double stop_coverage);
  double ballRadius(int s, double cap) const { return std::min(samples_.depth[std::size_t(s)] + protrusion_, cap); }
  // A ball counts a sample as covered only with this margin to spare, so that the space between samples is
  // covered too and not only the samples (without it the union keeps small voids between the balls).
  double margin() const { return 0.5 * samples_.grid.h; }
  double coverRadius(double r) const { return std::max(0.0, r - margin()); }
  std::int64_t stopCount() const { return stop_count_; }
  double protrusion() const { return protrusion_; }
  const InteriorSamples& samples() const { return samples_; }
  // One cover with radius cap `cap`, stopping at `max_count` balls or at the stop coverage.
  SphereCover run(double cap, int max_count) const;

 private:
  const InteriorSamples& samples_;
  double protrusion_;
  std::int64_t stop_count_;
};

// The cover with the cap tuned so that it needs about `target_spheres` balls, cut to that count.
SphereCover coverNearTarget(const GreedyCover& cover, double volume, const PackingOptions& opt);

// Radius tightening: each sphere shrinks to the smallest radius >= its inscribed radius D that still covers the
// samples no other sphere covers. Returns the sphere centres; `radius` is updated in place.
std::vector<Vec3d> tightenRadii(const GreedyCover& cover, const std::vector<int>& chosen, std::vector<double>& radius);

// Grows spheres to join groups detached by a gap of at most `max_gap`; returns how many spheres grew.
int bridgeNarrowGaps(const std::vector<Vec3d>& centre, std::vector<double>& radius, double max_gap);

}  // namespace inc::pack
