// StrokeSupports: a stroke's visibility-filtered supports, updated per new strip and point (= visibleSupports).
#include "host/cut/cut_stroke_supports.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "base/parallel.h"
#include "model/input_error.h"
#include "physics/distance.h"

namespace inc {

namespace {

struct Box {
  Vec3d lo, hi;
  bool empty = true;
};

Box surfaceBox(const SweptSurface& s) {
  Box b;
  for (const auto& t : s.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vec3d& v = s.vertices[std::size_t(t[std::size_t(k)])];
      if (b.empty) b.lo = b.hi = v, b.empty = false;
      for (int a = 0; a < 3; ++a) b.lo[a] = std::min(b.lo[a], v[a]), b.hi[a] = std::max(b.hi[a], v[a]);
    }
  return b;
}

// visibleSupports' "p lies near the cut": distanceToSweptSurface <= reach. A point farther than 2 reach outside
// the surface's box (in one coordinate) is farther than reach from every triangle whatever the rounding, so the
// box only skips the distance where it cannot decide. The query's distance is distanceToSweptSurface's, bit for bit.
bool withinReach(const SweptSurfaceQuery& s, const Box& box, const Vec3d& p, double reach) {
  if (box.empty) return false;
  for (int a = 0; a < 3; ++a)
    if (p[a] < box.lo[a] - 2.0 * reach || p[a] > box.hi[a] + 2.0 * reach) return false;
  return s.distance(p) <= reach;
}

// Whether p lies "by" `box`, a surface's box: an end of a pair (at most h long) that crosses one of its triangles
// does (crossesTriangle rejects a segment that misses the triangle's box widened by 1e-6 of its extent + 1e-12,
// so the end lies within h + that margin), and so do both ends of a pair with one end near the surface (within
// reach, about h, of it: the other end within about 2 h). 3 h leaves room for every rounding.
bool byBox(const Box& box, const Vec3d& p, double h) {
  if (box.empty) return false;
  for (int a = 0; a < 3; ++a) {
    const double pad = 3.0 * h + 1e-6 * (box.hi[a] - box.lo[a]) + 1e-12;
    if (p[a] < box.lo[a] - pad || p[a] > box.hi[a] + pad) return false;
  }
  return true;
}

// Appends the triangles of `from` from `first` on, each with its own copy of its three vertices (in its order:
// the crossing and distance tests of a triangle depend only on its vertices, so they decide exactly as in `from`).
void appendTriangles(SweptSurface& into, const SweptSurface& from, std::size_t first) {
  for (std::size_t t = first; t < from.triangles.size(); ++t) {
    const int base = int(into.vertices.size());
    for (int k = 0; k < 3; ++k) into.vertices.push_back(from.vertices[std::size_t(from.triangles[t][std::size_t(k)])]);
    into.triangles.push_back({base, base + 1, base + 2});
  }
}

// Keeps the entries marked kept, in place (no fresh buffers: the lists are rewritten every conversion).
void compact(NeighborLists& lists, const std::vector<char>& keep) {
  std::size_t w = 0;
  for (std::size_t q = 0; q + 1 < lists.offsets.size(); ++q) {
    const std::int64_t k0 = lists.offsets[q], k1 = lists.offsets[q + 1];
    lists.offsets[q] = std::int64_t(w);
    for (std::int64_t k = k0; k < k1; ++k)
      if (keep[std::size_t(k)]) lists.indices[w++] = lists.indices[std::size_t(k)];
  }
  lists.offsets.back() = std::int64_t(w);
  lists.indices.resize(w);
}

// Points binned in cells of edge >= h over their box (x fastest), sorted by cell (a counting sort, stable:
// ascending index within a cell). The edge grows where the box would need more than 64 cells a point.
class CellGrid {
 public:
  CellGrid(const std::vector<Vec3d>& x, double h) {
    Vec3d hi = x.front();
    lo_ = x.front();
    for (const Vec3d& p : x)
      for (int a = 0; a < 3; ++a) lo_[a] = std::min(lo_[a], p[a]), hi[a] = std::max(hi[a], p[a]);
    double edge = h;
    for (;;) {
      inv_ = 1.0 / edge;
      double cells = 1.0;
      for (int a = 0; a < 3; ++a) cells *= std::floor((hi[a] - lo_[a]) * inv_) + 1.0;
      if (cells <= 64.0 * double(x.size()) + 1024.0) break;
      edge *= 2.0;
    }
    for (int a = 0; a < 3; ++a) dims_[a] = std::int64_t(std::floor((hi[a] - lo_[a]) * inv_)) + 1;
    start_.assign(std::size_t(dims_[0] * dims_[1] * dims_[2] + 1), 0);
    std::vector<std::int64_t> cell(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      const auto c = cellOf(x[i]);
      cell[i] = c[0] + dims_[0] * (c[1] + dims_[1] * c[2]);
      ++start_[std::size_t(cell[i]) + 1];
    }
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    points_.resize(x.size());
    std::vector<std::int32_t> at(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < x.size(); ++i) points_[std::size_t(at[std::size_t(cell[i])]++)] = std::int32_t(i);
  }
  // The cell of p, clamped to the grid (every binned point lies inside it).
  std::array<std::int64_t, 3> cellOf(const Vec3d& p) const {
    std::array<std::int64_t, 3> c{};
    for (int a = 0; a < 3; ++a)
      c[std::size_t(a)] = std::clamp(std::int64_t(std::floor((p[a] - lo_[a]) * inv_)), std::int64_t(0), dims_[a] - 1);
    return c;
  }
  // The first point of cell (i, j, k) in the sorted order (i may be one past the row's last cell).
  const std::int32_t* cellBegin(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return points_.data() + start_[std::size_t(i + dims_[0] * (j + dims_[1] * k))];
  }

 private:
  Vec3d lo_;
  double inv_ = 1.0;
  std::int64_t dims_[3] = {1, 1, 1};
  std::vector<std::int32_t> start_;   // per cell, its first slot in points_ (plus one past the end)
  std::vector<std::int32_t> points_;  // point indices sorted by cell
};

}  // namespace

StrokeSupports::StrokeSupports(double h, std::vector<const SweptSurface*> earlier)
    : h_(h), earlier_(std::move(earlier)) {
  reach_ = h * (1.0 + 1e-9) + 1e-12;  // as visibleSupports (host/cut/cut_nodal_points.cpp)
  clear();
}

void StrokeSupports::clear() {
  stroke_ = SweptSurface{};
  lists_ = NeighborLists{};
  lists_.offsets.assign(1, 0);
  near_earlier_.clear();
  near_stroke_.clear();
  removed_ = 0;
}

bool StrokeSupports::extendsStroke(const SweptSurface& stroke) const {
  if (stroke.triangles.size() < stroke_.triangles.size()) return false;
  for (std::size_t t = 0; t < stroke_.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3d& a = stroke_.vertices[3 * t + std::size_t(k)];
      const Vec3d& b = stroke.vertices[std::size_t(stroke.triangles[t][std::size_t(k)])];
      if (!(a.x == b.x && a.y == b.y && a.z == b.z)) return false;
    }
  return true;
}

void StrokeSupports::update(const std::vector<Vec3d>& x, const SweptSurface& stroke) {
  // Checked here, where visibleSupports checks them (a region may be built before its radius is usable).
  if (!(h_ > 0.0)) throw InputError("cut", "support_radius", "must be positive");
  if (!extendsStroke(stroke)) {
    // Not the stroke seen so far: the lists start over (every point new) against this one.
    clear();
    appendTriangles(stroke_, stroke, 0);
  } else if (stroke.triangles.size() > stroke_.triangles.size()) {
    SweptSurface fresh;
    appendTriangles(fresh, stroke, stroke_.triangles.size());
    applyStrip(x, fresh);
  }
  appendPoints(x);
}

std::size_t StrokeSupports::extend(const std::vector<Vec3d>& x, const SweptSurface& fresh) {
  if (x.size() != pointCount()) throw InputError("cut", "points", "the strip is applied to the listed points only");
  return applyStrip(x, fresh);
}

// The listed pairs against the grown stroke S0 + F. A pair needs a test only when both ends are near S0 + F: if
// both were near S0 already it did not cross S0 (it was kept), so only F can drop it, and only when both ends lie
// by F's box; otherwise the whole stroke decides (an end that only now comes near lets S0's crossing count too),
// and both ends lie by F's box as one is near F. So only the rows of points by F's box are visited, and each entry
// decides its pair (lower index first) on its own: the mirror entry, in a visited row too, gets the same answer.
std::size_t StrokeSupports::applyStrip(const std::vector<Vec3d>& x, const SweptSurface& fresh) {
  const std::size_t n = pointCount();
  if (fresh.empty()) return 0;
  const Box fresh_box = surfaceBox(fresh);
  std::vector<char> near_fresh(n, 0), by_fresh(n, 0);
  const SweptSurfaceQuery strip(fresh);
  cpu::parallelFor(std::int64_t(n), [&](std::int64_t i) {
    by_fresh[std::size_t(i)] = byBox(fresh_box, x[std::size_t(i)], h_) ? 1 : 0;
    near_fresh[std::size_t(i)] =
        by_fresh[std::size_t(i)] && withinReach(strip, fresh_box, x[std::size_t(i)], reach_) ? 1 : 0;
  });
  appendTriangles(stroke_, fresh, 0);
  const SweptSurfaceQuery whole(stroke_);
  const auto nearNow = [&](std::size_t i) { return near_stroke_[i] || near_fresh[i]; };
  const auto drop = [&](std::size_t a, std::size_t b) {  // a < b, both near S0 + F and by F's box
    return (near_stroke_[a] && near_stroke_[b] ? strip : whole).segmentCrosses(x[a], x[b]);
  };
  std::vector<char> keep(lists_.indices.size(), 1);
  cpu::parallelFor(std::int64_t(n), [&](std::int64_t row) {  // each row writes its own entries only
    const std::size_t a = std::size_t(row);
    if (!by_fresh[a] || !nearNow(a)) return;
    for (std::int64_t k = lists_.offsets[a]; k < lists_.offsets[a + 1]; ++k) {
      const std::size_t b = std::size_t(lists_.indices[std::size_t(k)]);
      if (by_fresh[b] && nearNow(b) && drop(std::min(a, b), std::max(a, b))) keep[std::size_t(k)] = 0;
    }
  });
  for (std::size_t i = 0; i < n; ++i) near_stroke_[i] = char(nearNow(i));
  const std::size_t dropped = std::size_t(std::count(keep.begin(), keep.end(), 0));
  if (dropped > 0) compact(lists_, keep);
  removed_ += dropped;
  return dropped;
}

// Rows of the new points x[n0..n): each point's neighbours within h (closed ball, d^2 = distance2Exact <= h^2 as
// the grid search decides), itself left out, ascending. Cells of edge >= h over all points (a counting sort, O(n)
// per call); a query scans the cells within 1.01 h of it, which hold every accepted neighbour whatever the
// rounding (the cell of a coordinate is monotone in it), so the distance alone decides the lists.
NeighborLists StrokeSupports::newRows(const std::vector<Vec3d>& x, std::size_t n0) const {
  const CellGrid grid(x, h_);
  const double r2 = h_ * h_, span = 1.01 * h_;
  // Rows in parallel (each its own buffer), then concatenated in order.
  std::vector<std::vector<std::int32_t>> found(x.size() - n0);
  cpu::parallelFor(std::int64_t(x.size() - n0), [&](std::int64_t r) {
    const std::size_t q = n0 + std::size_t(r);
    std::vector<std::int32_t>& row = found[std::size_t(r)];
    const Vec3d& p = x[q];
    const auto lo = grid.cellOf(p - Vec3d(span, span, span)), hi = grid.cellOf(p + Vec3d(span, span, span));
    for (std::int64_t k = lo[2]; k <= hi[2]; ++k)
      for (std::int64_t j = lo[1]; j <= hi[1]; ++j) {
        // one row of cells is one run of the sorted points
        const std::int32_t* first = grid.cellBegin(lo[0], j, k);
        const std::int32_t* last = grid.cellBegin(hi[0] + 1, j, k);
        for (const std::int32_t* c = first; c < last; ++c) {
          const Vec3d d = p - x[std::size_t(*c)];
          // a cheap reject far outside the ball (the exact test decides the rest)
          if (d.x * d.x + d.y * d.y + d.z * d.z > r2 * (1.0 + 1e-9)) continue;
          if (std::size_t(*c) != q && distance2Exact(p, x[std::size_t(*c)]) <= r2) row.push_back(*c);
        }
      }
    std::sort(row.begin(), row.end());
  });
  NeighborLists rows;
  rows.offsets.assign(x.size() - n0 + 1, 0);
  for (std::size_t r = 0; r < found.size(); ++r) rows.offsets[r + 1] = rows.offsets[r] + std::int64_t(found[r].size());
  rows.indices.resize(std::size_t(rows.offsets.back()));
  for (std::size_t r = 0; r < found.size(); ++r)
    std::copy(found[r].begin(), found[r].end(), rows.indices.begin() + rows.offsets[r]);
  return rows;
}

// visibleSupports' decision for the pair a < b: some cut both ends lie near is crossed.
bool StrokeSupports::crosses(const std::vector<Vec3d>& x, std::size_t a, std::size_t b,
                             const std::vector<SweptSurfaceQuery>& earlier, const SweptSurfaceQuery& stroke) const {
  if (crossesACutNearBoth(near_earlier_[a], near_earlier_[b], earlier, x[a], x[b])) return true;
  return near_stroke_[a] && near_stroke_[b] && stroke.segmentCrosses(x[a], x[b]);
}

// The new points' rows filtered by visibleSupports' decision for each pair (lower index first), then every
// listed point's list extended by the new points that kept it (they come after all of its listed neighbours, so
// it stays ascending).
void StrokeSupports::appendPoints(const std::vector<Vec3d>& x) {
  const std::size_t n0 = pointCount(), n = x.size();
  if (n <= n0) return;
  // Which cuts each new point lies near.
  near_earlier_.resize(n);
  near_stroke_.resize(n, 0);
  const Box stroke_box = surfaceBox(stroke_);
  std::vector<SweptSurfaceQuery> earlier_queries;
  earlier_queries.reserve(earlier_.size());
  for (const SweptSurface* c : earlier_) earlier_queries.emplace_back(*c);
  const SweptSurfaceQuery stroke_query(stroke_);
  std::vector<Box> earlier_boxes;
  for (const SweptSurface* c : earlier_) earlier_boxes.push_back(surfaceBox(*c));
  cpu::parallelFor(std::int64_t(n - n0), [&](std::int64_t r) {  // each new point its own entries
    const std::size_t i = n0 + std::size_t(r);
    for (std::size_t c = 0; c < earlier_.size(); ++c)
      if (withinReach(earlier_queries[c], earlier_boxes[c], x[i], reach_)) near_earlier_[i].push_back(std::uint32_t(c));
    near_stroke_[i] = withinReach(stroke_query, stroke_box, x[i], reach_) ? 1 : 0;
  });
  const NeighborLists rows = newRows(x, n0);  // row r: point n0 + r
  std::vector<char> keep(rows.indices.size(), 1);
  std::vector<std::size_t> row_removed(n - n0, 0);
  cpu::parallelFor(std::int64_t(n - n0), [&](std::int64_t row) {  // each row its own entries and count
    const std::size_t r = std::size_t(row), q = n0 + r;
    for (std::int64_t k = rows.offsets[r]; k < rows.offsets[r + 1]; ++k) {
      const std::size_t j = std::size_t(rows.indices[std::size_t(k)]);
      if (j < n0) {
        keep[std::size_t(k)] = crosses(x, j, q, earlier_queries, stroke_query) ? 0 : 1;
        row_removed[r] += keep[std::size_t(k)] ? 0 : 2;  // this entry and the mirror j's list would hold
      } else {  // two new points: each row decides the pair (lower index first), so both get the same answer
        keep[std::size_t(k)] = crosses(x, std::min(j, q), std::max(j, q), earlier_queries, stroke_query) ? 0 : 1;
        row_removed[r] += keep[std::size_t(k)] ? 0 : 1;
      }
    }
  });
  for (std::size_t c : row_removed) removed_ += c;
  mergeRows(rows, keep);
}

// The listed points' lists, each followed by the new points that kept it (visited in order, so ascending), then
// the new points' kept rows. Written into the spare lists, which then swap with the current ones: both keep their
// storage over the stroke (fresh buffers of this size are fresh pages every conversion).
void StrokeSupports::mergeRows(const NeighborLists& rows, const std::vector<char>& keep) {
  const std::size_t n0 = lists_.queryCount(), added = rows.queryCount(), n = n0 + added;
  std::vector<std::int64_t> extra(n0, 0), kept(added, 0);
  for (std::size_t r = 0; r < added; ++r)
    for (std::int64_t k = rows.offsets[r]; k < rows.offsets[r + 1]; ++k) {
      if (!keep[std::size_t(k)]) continue;
      ++kept[r];
      if (std::size_t(rows.indices[std::size_t(k)]) < n0) ++extra[std::size_t(rows.indices[std::size_t(k)])];
    }
  NeighborLists& out = spare_;
  out.offsets.resize(n + 1);
  out.offsets[0] = 0;
  for (std::size_t i = 0; i < n0; ++i) out.offsets[i + 1] = out.offsets[i] + std::int64_t(lists_.count(i)) + extra[i];
  for (std::size_t r = 0; r < added; ++r) out.offsets[n0 + r + 1] = out.offsets[n0 + r] + kept[r];
  out.indices.resize(std::size_t(out.offsets[n]));
  std::vector<std::int64_t> at(n0);  // where listed point i's next added neighbour goes
  for (std::size_t i = 0; i < n0; ++i)
    at[i] = std::copy(lists_.indices.begin() + lists_.offsets[i], lists_.indices.begin() + lists_.offsets[i + 1],
                      out.indices.begin() + out.offsets[i]) -
            out.indices.begin();
  for (std::size_t r = 0; r < added; ++r) {
    std::int64_t w = out.offsets[n0 + r];
    for (std::int64_t k = rows.offsets[r]; k < rows.offsets[r + 1]; ++k) {
      if (!keep[std::size_t(k)]) continue;
      const std::int32_t j = rows.indices[std::size_t(k)];
      out.indices[std::size_t(w++)] = j;
      if (std::size_t(j) < n0) out.indices[std::size_t(at[std::size_t(j)]++)] = std::int32_t(n0 + r);
    }
  }
  std::swap(lists_, spare_);
}

}  // namespace inc
