// Uniform-grid cell keys, bucket hashing, Morton keys and the per-query cell traversal shared by the CPU and CUDA
// neighbour searches.
#pragma once

#include <cstddef>
#include <cstdint>

#include "physics/distance.h"
#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc {

// Cells per axis are clamped to [0, kNeighborGridMaxCells): 21 bits, so a cell packs into a 63-bit key.
constexpr std::int32_t kNeighborGridMaxCells = 1 << 21;
// Morton keys use 10 bits per axis (a 30-bit key); finer grids are coarsened by a shift (see neighborMortonKey).
constexpr std::int32_t kNeighborMortonBits = 10;

// Machine constants written out so that device code needs no std::numeric_limits.
template <typename T>
struct NeighborFloatTraits;
template <>
struct NeighborFloatTraits<float> {
  static constexpr float epsilon = 1.1920928955078125e-7f;           // 2^-23
  static constexpr float sqrt_min_normal = 1.0842021724855044e-19f;  // sqrt(2^-126) = 2^-63
};
template <>
struct NeighborFloatTraits<double> {
  static constexpr double epsilon = 2.220446049250313e-16;            // 2^-52
  static constexpr double sqrt_min_normal = 1.4916681462400413e-154;  // sqrt(2^-1022) = 2^-511
};

// Everything a query needs to know about the grid. Built by makeNeighborGridParams from the bounding box of
// the finite points (on the device this happens in a one-thread kernel, so the host never needs the box).
template <typename T>
struct NeighborGridParams {
  Vec3<T> origin;             // lower corner of the points' bounding box (cell (0,0,0) starts here)
  T inv_cell;                 // 1 / cell size (y and z)
  T inv_cell_x;               // 1 / cell size along x: x_refine / cell size (see makeNeighborGridParams)
  std::int32_t dims[3];       // occupied cells per axis (after clamping); 0 when there are no finite points
  std::uint32_t bucket_mask;  // bucket count - 1 (the bucket count is a power of two, about 2 n)
  std::int32_t dense;         // 1: bucket = row-major cell index (no collisions); 0: bucket = hash & mask
  std::int32_t morton_shift;  // Morton keys use (cell >> morton_shift), 10 bits per axis
  std::int64_t first_bad;     // index of the first non-finite point, or n when all are finite
};

// Bucket count for n points: the power of two >= 2 n (at least 2). Host only: it sizes the start table.
inline std::uint32_t neighborBucketCount(std::size_t n) {
  std::uint64_t m = 2;
  while (m < 2 * std::uint64_t(n)) m <<= 1;
  return std::uint32_t(m);  // n <= 2^30 is checked by the callers, so m <= 2^31
}

// The cell coordinate of x along one axis: floor((x - origin) / h), clamped to [0, kNeighborGridMaxCells).
// It is monotone non-decreasing in x (rounding is monotone, so is the clamp), which is all the traversal's
// exactness argument needs; NaN maps to 0 so that unvalidated input cannot cause undefined conversions.
template <typename T>
INC_HD std::int32_t neighborCellCoord(T x, T origin, T inv_cell) {
  const T v = (x - origin) * inv_cell;
  if (!(v >= T(0))) return 0;
  if (v >= T(kNeighborGridMaxCells - 1)) return kNeighborGridMaxCells - 1;
  return std::int32_t(v);  // v >= 0, so truncation is floor
}

// Integer mixer (a 64-bit finaliser: xor-shift / odd multiply rounds) so that every key bit reaches the low
// bits that the bucket mask keeps; plain products of coordinates would collide for cells a power of two apart.
INC_HD std::uint32_t neighborCellHash(std::int32_t cx, std::int32_t cy, std::int32_t cz) {
  std::uint64_t k = std::uint64_t(cx) | (std::uint64_t(cy) << 21) | (std::uint64_t(cz) << 42);
  k ^= k >> 31;
  k *= 0x7fb5d329728ea185ULL;
  k ^= k >> 27;
  k *= 0x81dadef4bc2dd44dULL;
  k ^= k >> 33;
  return std::uint32_t(k);
}

template <typename T>
INC_HD std::uint32_t neighborBucket(const NeighborGridParams<T>& p, std::int32_t cx, std::int32_t cy, std::int32_t cz) {
  if (p.dense)  // dims[0] * dims[1] * dims[2] <= bucket count <= 2^31, so this cannot overflow
    return std::uint32_t(cx) +
           std::uint32_t(p.dims[0]) * (std::uint32_t(cy) + std::uint32_t(p.dims[1]) * std::uint32_t(cz));
  return neighborCellHash(cx, cy, cz) & p.bucket_mask;
}

// Spreads the low 10 bits of v so that two zero bits follow each one (for interleaving three axes).
INC_HD std::uint32_t neighborSpreadBits10(std::uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

// Z-order key of a cell: exact cell order when every axis has <= 1024 cells, else the order of blocks of
// 2^morton_shift cells per axis (points inside one block keep their previous relative order).
template <typename T>
INC_HD std::uint32_t neighborMortonKey(const NeighborGridParams<T>& p, std::int32_t cx, std::int32_t cy,
                                       std::int32_t cz) {
  const int s = p.morton_shift;
  return neighborSpreadBits10(std::uint32_t(cx) >> s) | (neighborSpreadBits10(std::uint32_t(cy) >> s) << 1) |
         (neighborSpreadBits10(std::uint32_t(cz) >> s) << 2);
}

template <typename T>
INC_HD bool neighborPointFinite(const Vec3<T>& x) {
  // x - x is 0 for finite values and NaN for NaN and +-inf (no <cmath> needed on the device)
  return (x.x - x.x) == T(0) && (x.y - x.y) == T(0) && (x.z - x.z) == T(0);
}

// A radius is usable when finite and >= 0.
template <typename T>
INC_HD bool neighborRadiusValid(T r) {
  return r >= T(0) && (r - r) == T(0);
}

// The cell edge along axis a: x may be cut finer than y and z (NeighborGridParams::inv_cell_x).
template <typename T>
INC_HD T neighborInvCell(const NeighborGridParams<T>& p, int a) {
  return a == 0 ? p.inv_cell_x : p.inv_cell;
}

// Largest factor by which the x cells of a dense grid are cut finer than the cell size.
constexpr int kNeighborMaxXRefine = 8;

// Grid parameters from the bounding box [lo, hi] of the finite points. n_finite == 0 gives an empty grid.
// A dense grid cuts its x cells k times finer than y and z (k = 8, 4, 2 or 1: the largest that keeps the grid
// dense). A dense row of cells (fixed y and z) is one contiguous run of slots, so finer x cells cost no
// extra lookups, and the run a query scans in each row (trimmed to the sphere's extent in that row, see
// neighborRowXRange) overshoots the sphere by at most one cell edge h/k instead of h: about a fifth fewer
// candidates per query for cells of one radius. Both backends call this, so they agree on every cell.
template <typename T>
INC_HD NeighborGridParams<T> makeNeighborGridParams(const Vec3<T>& lo, const Vec3<T>& hi, T cell_size,
                                                    std::uint32_t bucket_count, std::int64_t first_bad,
                                                    bool any_finite) {
  NeighborGridParams<T> p;
  p.origin = lo;
  p.inv_cell = T(1) / cell_size;
  p.inv_cell_x = p.inv_cell;
  p.bucket_mask = bucket_count - 1u;
  p.first_bad = first_bad;
  std::uint64_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    p.dims[a] = any_finite ? neighborCellCoord(hi[a], lo[a], p.inv_cell) + 1 : 0;
    cells *= std::uint64_t(p.dims[a]);  // each <= 2^21, so the product fits in 64 bits
  }
  p.dense = cells <= std::uint64_t(bucket_count) ? 1 : 0;
  if (p.dense && any_finite) {
    const std::uint64_t yz = std::uint64_t(p.dims[1]) * std::uint64_t(p.dims[2]);
    for (int k = kNeighborMaxXRefine; k > 1; k /= 2) {
      const T inv_x = p.inv_cell * T(k);
      const std::int32_t dx = neighborCellCoord(hi[0], lo[0], inv_x) + 1;
      if (std::uint64_t(dx) * yz <= std::uint64_t(bucket_count) && (inv_x - inv_x) == T(0)) {
        p.inv_cell_x = inv_x;
        p.dims[0] = dx;
        break;
      }
    }
  }
  std::int32_t max_dim = 0;
  for (int a = 0; a < 3; ++a) max_dim = p.dims[a] > max_dim ? p.dims[a] : max_dim;
  int bits = 0;
  while (bits < 21 && (std::int32_t(1) << bits) < max_dim) ++bits;
  p.morton_shift = bits > kNeighborMortonBits ? bits - kNeighborMortonBits : 0;
  return p;
}

// Read-only view of a built grid: points in storage order, the bucket start table (bucket count + 1 entries)
// and, when the storage order is not the bucket order (Morton mode), the storage index of each bucket slot.
template <typename T>
struct NeighborGridView {
  NeighborGridParams<T> p;
  const Vec3<T>* points;             // storage order
  const std::int32_t* bucket_start;  // slots of bucket b: [bucket_start[b], bucket_start[b + 1])
  const std::int32_t* entries;       // storage index of each slot; nullptr means slot == storage index
  std::int32_t n;
  INC_HD Vec3<T> point(std::int32_t j) const { return points[j]; }
};

// Half-width of the per-axis cell range searched for radius r. Any pair accepted by
// distance2Exact(x, y) <= fl(r * r) has |x_a - y_a| <= r (1 + 2 eps) + sqrt(min normal) in exact arithmetic
// (each of the 5 roundings is relative <= eps/2 on non-negative terms; underflow adds at most sqrt(min));
// 16 eps leaves room for the rounding of this expression itself. See docs/neighbor-search.md.
template <typename T>
INC_HD T neighborSearchReach(T r) {
  return r * (T(1) + T(16) * NeighborFloatTraits<T>::epsilon) + NeighborFloatTraits<T>::sqrt_min_normal;
}

// Lower bound on |c - y| for every y whose cell coordinate along one axis is `cell`, where `c_cell` is the
// query coordinate's own cell (0 when they are equal). Cell `cell` holds values with fl((y - o) h^-1) in
// [cell, cell + 1) (or clamped there from outside); the boundary o + cell h is then exact to within a few
// roundings of |o| + |c| + (|cell| + 1) h, and 8 eps of that is subtracted so the bound never overshoots.
template <typename T>
INC_HD T neighborAxisGap(T c, std::int32_t c_cell, std::int32_t cell, T origin, T h) {
  if (cell == c_cell) return T(0);
  const T ac = c < T(0) ? -c : c, ao = origin < T(0) ? -origin : origin;
  const T slack =
      T(8) * NeighborFloatTraits<T>::epsilon * (ao + ac + T(cell + 1) * h) + NeighborFloatTraits<T>::sqrt_min_normal;
  const T gap = cell > c_cell ? (origin + T(cell) * h) - c : c - (origin + T(cell + 1) * h);
  const T g = gap - slack;
  return g > T(0) ? g : T(0);
}

// Trims the x-range [lo_x, hi_x] of cells searched in the (cy, cz) row of cells for a query at x with search
// reach `reach`: a point of that row is at least gy, gz away in y and z, so it can only be accepted if its x
// lies within sqrt(reach^2 - gy^2 - gz^2) of x. Returns false when no point of the row can be accepted.
// The reach^2 term is inflated by 32 eps to absorb the rounding of the subtraction, and the square root by
// 4 eps; the x bounds then go through the same monotone cell function (exact argument: fl is monotone and
// every point coordinate is a float, see forEachGridNeighbor). Rows are only ever trimmed, never widened.
template <typename T>
INC_HD bool neighborRowXRange(const NeighborGridParams<T>& p, const Vec3<T>& x, T reach, const std::int32_t qc[3],
                              std::int32_t cy, std::int32_t cz, std::int32_t& lo_x, std::int32_t& hi_x) {
  const T h = T(1) / p.inv_cell;
  const T gy = neighborAxisGap(x.y, qc[1], cy, p.origin.y, h);
  const T gz = neighborAxisGap(x.z, qc[2], cz, p.origin.z, h);
  if (gy == T(0) && gz == T(0)) return true;  // the query's own row: the full reach applies
  const T w2 = reach * reach * (T(1) + T(32) * NeighborFloatTraits<T>::epsilon) - gy * gy - gz * gz;
  if (w2 < T(0)) return false;
  const T w = std::sqrt(w2) * (T(1) + T(4) * NeighborFloatTraits<T>::epsilon) + NeighborFloatTraits<T>::sqrt_min_normal;
  const std::int32_t a = neighborCellCoord(x.x - w, p.origin.x, p.inv_cell_x);
  const std::int32_t b = neighborCellCoord(x.x + w, p.origin.x, p.inv_cell_x);
  if (a > lo_x) lo_x = a;
  if (b < hi_x) hi_x = b;
  return lo_x <= hi_x;
}

namespace detail {
template <typename T, typename View, typename Visit>
INC_HD void neighborTest(const View& g, const Vec3<T>& x, T r2, std::int32_t j, std::int32_t skip, Visit& visit) {
  if (j != skip && distance2Exact(x, g.point(j)) <= r2) visit(j);
}

template <typename T, typename Visit>
INC_HD void neighborTestPoint(const Vec3<T>& x, const Vec3<T>& y, T r2, std::int32_t j, std::int32_t skip,
                              Visit& visit) {
  if (j != skip && distance2Exact(x, y) <= r2) visit(j);
}

// One contiguous run of slots [e, e1) of a dense grid, in slot order. Four candidates are loaded before the
// first of them is tested: the loop is bound by the latency of those loads, and independent loads overlap.
template <typename T, typename View, typename Visit>
INC_HD void neighborScanRun(const View& g, const Vec3<T>& x, T r2, std::int32_t e, std::int32_t e1, std::int32_t skip,
                            Visit& visit) {
  for (; e + 4 <= e1; e += 4) {
    const std::int32_t j0 = g.entries ? g.entries[e] : e, j1 = g.entries ? g.entries[e + 1] : e + 1,
                       j2 = g.entries ? g.entries[e + 2] : e + 2, j3 = g.entries ? g.entries[e + 3] : e + 3;
    const Vec3<T> y0 = g.point(j0), y1 = g.point(j1), y2 = g.point(j2), y3 = g.point(j3);
    neighborTestPoint(x, y0, r2, j0, skip, visit);
    neighborTestPoint(x, y1, r2, j1, skip, visit);
    neighborTestPoint(x, y2, r2, j2, skip, visit);
    neighborTestPoint(x, y3, r2, j3, skip, visit);
  }
  for (; e < e1; ++e) neighborTest(g, x, r2, g.entries ? g.entries[e] : e, skip, visit);
}
}  // namespace detail

// Calls visit(j) for every storage index j != skip with distance2Exact(x, points[j]) <= r * r, each exactly
// once, in an order that depends only on the grid (not on threads). The cell range per axis is
// [cell(x - reach), cell(x + reach)] with the same monotone cell function that placed the points, so no
// accepted point can lie outside it, whatever r is relative to the cell size.
//  - dense grids: buckets are cells; one (y, z) row of cells is one contiguous run of slots.
//  - hashed grids: two cells of the range can share a bucket; a slot is only taken when its point's own
//    cell is the cell being visited, so a point is never listed twice.
//  - when the range has more cells than there are points, every point is scanned instead.
// View is NeighborGridView<T> or a device view with the same members whose point(j) reads a packed copy
// of the same coordinates (kernels/neighbor_search_cuda.cu: float4 loads).
template <typename T, typename View, typename Visit>
INC_HD void forEachGridNeighbor(const View& view, const Vec3<T>& query, T r, std::int32_t skip, Visit& visit) {
  // Local copies: the visitor writes memory, and without them the compiler must assume that those writes
  // may change the view or the query point, reloading them for every candidate.
  const View g = view;
  const Vec3<T> x = query;
  if (g.n <= 0) return;
  const NeighborGridParams<T>& p = g.p;
  const T r2 = r * r;
  const T reach = neighborSearchReach(r);
  std::int32_t lo[3], hi[3];
  std::uint64_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    lo[a] = neighborCellCoord(x[a] - reach, p.origin[a], neighborInvCell(p, a));
    const std::int32_t h = neighborCellCoord(x[a] + reach, p.origin[a], neighborInvCell(p, a));
    hi[a] = h < p.dims[a] - 1 ? h : p.dims[a] - 1;
    if (lo[a] > hi[a]) return;  // the range misses every occupied cell
    cells *= std::uint64_t(hi[a] - lo[a] + 1);
  }
  if (cells > std::uint64_t(g.n)) {
    for (std::int32_t j = 0; j < g.n; ++j) detail::neighborTest(g, x, r2, j, skip, visit);
    return;
  }
  // The query's own cell (the rows that share its y or z are not trimmed in that axis).
  const std::int32_t qc[3] = {neighborCellCoord(x.x, p.origin.x, p.inv_cell_x),
                              neighborCellCoord(x.y, p.origin.y, p.inv_cell),
                              neighborCellCoord(x.z, p.origin.z, p.inv_cell)};
  if (p.dense) {
    for (std::int32_t cz = lo[2]; cz <= hi[2]; ++cz)
      for (std::int32_t cy = lo[1]; cy <= hi[1]; ++cy) {
        std::int32_t xl = lo[0], xh = hi[0];
        if (!neighborRowXRange(p, x, reach, qc, cy, cz, xl, xh)) continue;
        const std::uint32_t b0 = neighborBucket(p, xl, cy, cz);
        const std::uint32_t b1 = b0 + std::uint32_t(xh - xl) + 1u;
        detail::neighborScanRun(g, x, r2, g.bucket_start[b0], g.bucket_start[b1], skip, visit);
      }
    return;
  }
  for (std::int32_t cz = lo[2]; cz <= hi[2]; ++cz)
    for (std::int32_t cy = lo[1]; cy <= hi[1]; ++cy) {
      std::int32_t xl = lo[0], xh = hi[0];
      if (!neighborRowXRange(p, x, reach, qc, cy, cz, xl, xh)) continue;
      for (std::int32_t cx = xl; cx <= xh; ++cx) {
        const std::uint32_t b = neighborBucket(p, cx, cy, cz);
        const std::int32_t e1 = g.bucket_start[b + 1u];
        for (std::int32_t e = g.bucket_start[b]; e < e1; ++e) {
          const std::int32_t j = g.entries ? g.entries[e] : e;
          const Vec3<T> y = g.point(j);
          if (neighborCellCoord(y.x, p.origin.x, p.inv_cell_x) != cx ||
              neighborCellCoord(y.y, p.origin.y, p.inv_cell) != cy ||
              neighborCellCoord(y.z, p.origin.z, p.inv_cell) != cz)
            continue;  // another cell that shares this bucket: it is visited (or not) on its own
          detail::neighborTest(g, x, r2, j, skip, visit);
        }
      }
    }
}

}  // namespace inc
