// Dense uniform grid over a subset of points: nearest member, any or every member within r (re-packing, graph repair).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "physics/vec3.h"

namespace inc {

// Members are indices into `x` (kept by reference: it must outlive the grid), inserted one by one. The grid covers
// the box [lo, hi] given at construction; a member or query outside it lands in the nearest border cell, and the
// queries widen their bounds by how far the query lies outside, so they stay exact. The cell edge is at least
// `cell`, grown when the box would need more than `max_cells` cells, so a small cell over a wide box stays cheap.
// Both queries are independent of the insertion order (ties go to the lower index): the results are those of any
// other exact search.
class PointGrid {
 public:
  PointGrid(const std::vector<Vec3d>& x, const Vec3d& lo, const Vec3d& hi, double cell, std::size_t max_cells)
      : x_(x), lo_(lo) {
    const Vec3d ext(std::max(hi.x - lo.x, 0.0), std::max(hi.y - lo.y, 0.0), std::max(hi.z - lo.z, 0.0));
    cell_ = cell;
    const auto count = [&](double c) {
      double total = 1.0;
      for (int k = 0; k < 3; ++k) total *= std::floor(ext[k] / c) + 1.0;
      return total;
    };
    while (count(cell_) > double(std::max<std::size_t>(max_cells, 1))) cell_ *= 1.25;
    for (int k = 0; k < 3; ++k) dim_[k] = std::int64_t(std::floor(ext[k] / cell_)) + 1;
    head_.assign(std::size_t(dim_[0] * dim_[1] * dim_[2]), -1);
  }

  double cell() const { return cell_; }

  // Adds member i; a repeated insert of the same index is ignored (the lists are linked through next_).
  void insert(std::int32_t i) {
    const std::int64_t c = cellIndex(coord(x_[std::size_t(i)]));
    if (std::size_t(i) >= next_.size()) next_.resize(std::size_t(i) + 1, kAbsent);
    if (next_[std::size_t(i)] != kAbsent) return;
    next_[std::size_t(i)] = head_[std::size_t(c)];
    head_[std::size_t(c)] = i;
    ++members_;
  }

  // Nearest member to p (its distance in `dist`), -1 when empty. Rings of cells outward from p's cell; every
  // member of ring R lies at least (R - 1) cells from p (p's cell may be a clamped border cell: the offset only
  // widens the bound's slack), so the search stops once the best distance is below that or the rings have
  // covered the whole grid.
  std::int32_t nearest(const Vec3d& p, double& dist) const {
    dist = std::numeric_limits<double>::infinity();
    std::int32_t best = -1;
    if (members_ == 0) return best;
    const Coord c = coord(p);
    const double off = outside(p);  // a member of ring R lies at least (R - 1) cells minus this from p
    const std::int64_t max_ring = std::max({dim_[0], dim_[1], dim_[2]});
    for (std::int64_t ring = 0; ring <= max_ring; ++ring) {
      if (best >= 0 && double(ring - 1) * cell_ - off > dist) break;
      forShell(c, ring, [&](std::int64_t cell) {
        for (std::int32_t i = head_[std::size_t(cell)]; i >= 0; i = next_[std::size_t(i)]) {
          const double q = norm(x_[std::size_t(i)] - p);
          if (q < dist || (q == dist && i < best)) dist = q, best = i;
        }
      });
    }
    return best;
  }

  // True when a member lies within r of p.
  bool anyWithin(const Vec3d& p, double r) const {
    bool any = false;
    forEachWithin(p, r, [&](std::int32_t) {
      any = true;
      return false;
    });
    return any;
  }

  // Calls visit(i) for the members within r of p, cell by cell, until visit returns false.
  template <typename Visit>
  void forEachWithin(const Vec3d& p, double r, Visit&& visit) const {
    if (members_ == 0) return;
    const std::int64_t reach = std::int64_t(std::ceil((r + outside(p)) / cell_));
    const Coord c = coord(p);
    const std::int64_t a0 = std::max<std::int64_t>(c.k[0] - reach, 0), a1 = std::min(c.k[0] + reach, dim_[0] - 1);
    const std::int64_t b0 = std::max<std::int64_t>(c.k[1] - reach, 0), b1 = std::min(c.k[1] + reach, dim_[1] - 1);
    const std::int64_t d0 = std::max<std::int64_t>(c.k[2] - reach, 0), d1 = std::min(c.k[2] + reach, dim_[2] - 1);
    for (std::int64_t a = a0; a <= a1; ++a)
      for (std::int64_t b = b0; b <= b1; ++b)
        for (std::int64_t d = d0; d <= d1; ++d)
          for (std::int32_t i = head_[std::size_t(cellIndex({{a, b, d}}))]; i >= 0; i = next_[std::size_t(i)])
            if (norm(x_[std::size_t(i)] - p) <= r && !visit(i)) return;
  }

 private:
  struct Coord {
    std::int64_t k[3];
  };
  // p's cell, clamped into the grid.
  Coord coord(const Vec3d& p) const {
    Coord c;
    for (int k = 0; k < 3; ++k) {
      const double v = std::floor((p[k] - lo_[k]) / cell_);
      c.k[k] = v < 0 ? 0 : (v >= double(dim_[k]) ? dim_[k] - 1 : std::int64_t(v));
    }
    return c;
  }
  // How far p lies outside the grid's cells (0 inside): clamping moved it by at most this much.
  double outside(const Vec3d& p) const {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double hi = lo_[k] + double(dim_[k]) * cell_;
      const double e = p[k] < lo_[k] ? lo_[k] - p[k] : (p[k] > hi ? p[k] - hi : 0.0);
      d2 += e * e;
    }
    return std::sqrt(d2);
  }
  std::int64_t cellIndex(const Coord& c) const { return (c.k[0] * dim_[1] + c.k[1]) * dim_[2] + c.k[2]; }
  // Calls f(cell index) for every grid cell at Chebyshev distance `ring` from c.
  template <typename F>
  void forShell(const Coord& c, std::int64_t ring, F&& f) const {
    for (std::int64_t a = -ring; a <= ring; ++a) {
      const std::int64_t ka = c.k[0] + a;
      if (ka < 0 || ka >= dim_[0]) continue;
      for (std::int64_t b = -ring; b <= ring; ++b) {
        const std::int64_t kb = c.k[1] + b;
        if (kb < 0 || kb >= dim_[1]) continue;
        const bool face = a == -ring || a == ring || b == -ring || b == ring;
        const std::int64_t step = face ? 1 : std::max<std::int64_t>(2 * ring, 1);
        for (std::int64_t d = -ring; d <= ring; d += step) {
          const std::int64_t kd = c.k[2] + d;
          if (kd < 0 || kd >= dim_[2]) continue;
          f(cellIndex({{ka, kb, kd}}));
        }
      }
    }
  }

  static constexpr std::int32_t kAbsent = -2;  // next_ of an index not inserted (-1 ends a cell's list)
  const std::vector<Vec3d>& x_;
  Vec3d lo_;
  double cell_ = 1.0;
  std::int64_t dim_[3] = {1, 1, 1};
  std::vector<std::int32_t> head_, next_;
  std::size_t members_ = 0;
};

}  // namespace inc
