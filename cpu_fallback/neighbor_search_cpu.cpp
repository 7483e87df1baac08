// CPU uniform-grid neighbour search: counting sort by bucket, shared traversal, one pass into per-block lists.
#include "cpu_fallback/neighbor_search_cpu.h"

#include <algorithm>
#include <limits>
#include <new>
#include <sstream>
#include <string>

#include "cpu_fallback/parallel.h"
#include "host/input_error.h"

namespace inc::cpu {
namespace {

constexpr std::size_t kMaxPoints = std::size_t(1) << 30;  // keeps the bucket count (2^31) and int32 indices safe

template <typename T>
std::string describe(const Vec3<T>& x) {
  std::ostringstream s;
  s << "(" << x.x << ", " << x.y << ", " << x.z << ")";
  return s.str();
}

template <typename T>
void checkCellSize(T h) {
  if (!(h > T(0)) || !neighborRadiusValid(h) || !neighborRadiusValid(T(1) / h))
    throw InputError("", "cell_size", "must be finite and > 0 with a finite inverse, got " + std::to_string(double(h)));
}

// Stable counting sort of `order` by keys[order[i]] < bucket_count; start gets bucket_count + 1 entries.
void countingSortByKey(const std::vector<std::uint32_t>& keys, std::uint32_t bucket_count,
                       std::vector<std::int32_t>& sorted, std::vector<std::int32_t>& start) {
  const std::size_t n = keys.size();
  start.assign(std::size_t(bucket_count) + 1, 0);
  for (std::size_t i = 0; i < n; ++i) ++start[keys[i] + 1];
  for (std::size_t b = 0; b < bucket_count; ++b) start[b + 1] += start[b];
  sorted.resize(n);
  // Fill back to front from each bucket's end: stable, and afterwards start[b + 1] == begin(b).
  for (std::size_t i = n; i-- > 0;) sorted[std::size_t(--start[keys[i] + 1])] = std::int32_t(i);
  std::copy(start.begin() + 1, start.end(), start.begin());
  start[bucket_count] = std::int32_t(n);
}

// Stable LSD radix sort of indices 0..n-1 by 30-bit keys (three 10-bit passes).
std::vector<std::int32_t> radixSortIndices(const std::vector<std::uint32_t>& keys) {
  const std::size_t n = keys.size();
  std::vector<std::int32_t> idx(n), tmp(n);
  for (std::size_t i = 0; i < n; ++i) idx[i] = std::int32_t(i);
  std::vector<std::int32_t> count(1025);
  for (int shift = 0; shift < 30; shift += 10) {
    std::fill(count.begin(), count.end(), 0);
    for (std::size_t i = 0; i < n; ++i) ++count[((keys[std::size_t(idx[i])] >> shift) & 1023u) + 1];
    for (int d = 0; d < 1024; ++d) count[std::size_t(d) + 1] += count[std::size_t(d)];
    for (std::size_t i = 0; i < n; ++i) tmp[std::size_t(count[(keys[std::size_t(idx[i])] >> shift) & 1023u]++)] = idx[i];
    idx.swap(tmp);
  }
  return idx;
}

// Lists are short (tens of entries): insertion sort beats std::sort's set-up there.
void sortList(std::int32_t* a, std::size_t k) {
  if (k > 32) {
    std::sort(a, a + k);
    return;
  }
  for (std::size_t i = 1; i < k; ++i) {
    const std::int32_t v = a[i];
    std::size_t j = i;
    for (; j > 0 && a[j - 1] > v; --j) a[j] = a[j - 1];
    a[j] = v;
  }
}

// Dense-grid fast path of forEachGridNeighbor (same cell range, same rows, same d^2 decision, so the same
// set; the caller sorts it): each (y, z) row of the range is one contiguous run of bucket slots, scanned over
// separate coordinate arrays with a branch-free append into `out` (room for every candidate: `capacity`
// grows as needed). Returns false where the generic traversal must be used (hashed grid, or a range with
// more cells than points); otherwise the number of neighbours written.
// No FMA contraction: d^2 must round exactly like distance2Exact ((dx^2 + dy^2) + dz^2, each rounded).
#if defined(__clang__)
#define INC_NO_CONTRACT_BEGIN  // clang: the pragma at the top of the function body
#define INC_NO_CONTRACT_END
#elif defined(__GNUC__)
#define INC_NO_CONTRACT_BEGIN _Pragma("GCC push_options") _Pragma("GCC optimize(\"fp-contract=off\")")
#define INC_NO_CONTRACT_END _Pragma("GCC pop_options")
#else
#define INC_NO_CONTRACT_BEGIN
#define INC_NO_CONTRACT_END
#endif

struct DenseRowsResult {
  bool handled;
  std::size_t count;
};

INC_NO_CONTRACT_BEGIN
template <typename T>
DenseRowsResult denseRows(const NeighborGridParams<T>& p, const std::int32_t* start, const T* xs, const T* ys,
                          const T* zs, const std::int32_t* orig, std::int32_t n, const Vec3<T>& x, T r,
                          std::int32_t skip_orig, std::vector<std::int32_t>& out) {
#if defined(__clang__)
#pragma clang fp contract(off)
#endif
  if (!p.dense) return {false, 0};
  if (n <= 0) return {true, 0};
  const T r2 = r * r;
  const T reach = neighborSearchReach(r);
  std::int32_t lo[3], hi[3];
  std::uint64_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    lo[a] = neighborCellCoord(x[a] - reach, p.origin[a], p.inv_cell);
    const std::int32_t h = neighborCellCoord(x[a] + reach, p.origin[a], p.inv_cell);
    hi[a] = h < p.dims[a] - 1 ? h : p.dims[a] - 1;
    if (lo[a] > hi[a]) return {true, 0};
    cells *= std::uint64_t(hi[a] - lo[a] + 1);
  }
  if (cells > std::uint64_t(n)) return {false, 0};
  // The slot run of each row after trimming (the same rows and ranges as forEachGridNeighbor), and room
  // for every candidate.
  const std::int32_t qc[3] = {neighborCellCoord(x.x, p.origin.x, p.inv_cell),
                              neighborCellCoord(x.y, p.origin.y, p.inv_cell),
                              neighborCellCoord(x.z, p.origin.z, p.inv_cell)};
  std::int32_t runs[2 * 64];
  int nrun = 0;
  std::size_t candidates = 0;
  if (std::uint64_t(hi[1] - lo[1] + 1) * std::uint64_t(hi[2] - lo[2] + 1) > 64) return {false, 0};
  for (std::int32_t cz = lo[2]; cz <= hi[2]; ++cz)
    for (std::int32_t cy = lo[1]; cy <= hi[1]; ++cy) {
      std::int32_t xl = lo[0], xh = hi[0];
      if (!neighborRowXRange(p, x, reach, qc, cy, cz, xl, xh)) continue;
      const std::uint32_t b0 = neighborBucket(p, xl, cy, cz);
      runs[2 * nrun] = start[b0];
      runs[2 * nrun + 1] = start[b0 + std::uint32_t(xh - xl) + 1u];
      candidates += std::size_t(runs[2 * nrun + 1] - runs[2 * nrun]);
      ++nrun;
    }
  if (out.size() < candidates) out.resize(candidates);
  std::int32_t* dst = out.data();
  std::size_t m = 0;
  const T qx = x.x, qy = x.y, qz = x.z;
  for (int k = 0; k < nrun; ++k) {
    const std::int32_t e1 = runs[2 * k + 1];
    for (std::int32_t e = runs[2 * k]; e < e1; ++e) {
      const T dx = qx - xs[e], dy = qy - ys[e], dz = qz - zs[e];
      const T xx = dx * dx, yy = dy * dy, zz = dz * dz;
      const T d2 = (xx + yy) + zz;
      const std::int32_t o = orig[e];
      dst[m] = o;
      m += std::size_t((d2 <= r2) & (o != skip_orig));
    }
  }
  return {true, m};
}
INC_NO_CONTRACT_END

// Appends perm[j] (original index), or j itself when perm is null (storage-order lists).
struct AppendIndex {
  std::vector<std::int32_t>* out;
  const std::int32_t* perm;
  void operator()(std::int32_t j) { out->push_back(perm ? perm[j] : j); }
};

}  // namespace

template <typename T>
void GridNeighborSearch<T>::build(const std::vector<Vec3<T>>& points, T cell_size, bool morton_order) {
  checkCellSize(cell_size);
  const std::size_t n = points.size();
  if (n > kMaxPoints)
    throw InputError("", "points", "too many points for the grid search (" + std::to_string(n) + " > 2^30)");
  for (std::size_t i = 0; i < n; ++i)
    if (!neighborPointFinite(points[i]))
      throw InputError("", "points[" + std::to_string(i) + "]", "position " + describe(points[i]) + " is not finite");
  cell_size_ = cell_size;
  morton_ = morton_order;

  Vec3<T> lo, hi;
  if (n > 0) lo = hi = points[0];
  for (const Vec3<T>& x : points)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], x[a]);
      hi[a] = std::max(hi[a], x[a]);
    }
  const std::uint32_t buckets = neighborBucketCount(n);
  params_ = makeNeighborGridParams(lo, hi, cell_size, buckets, std::int64_t(n), n > 0);
  const NeighborGridParams<T> p = params_;
  auto cellOf = [&p](const Vec3<T>& x, std::int32_t c[3]) {
    for (int a = 0; a < 3; ++a) c[a] = neighborCellCoord(x[a], p.origin[a], p.inv_cell);
  };

  std::vector<std::uint32_t> keys(n);
  if (morton_order) {
    // Z order first (stable), then a stable bucket sort of the storage slots gives the lookup table.
    parallelFor(std::int64_t(n), [&](std::int64_t i) {
      std::int32_t c[3];
      cellOf(points[std::size_t(i)], c);
      keys[std::size_t(i)] = neighborMortonKey(p, c[0], c[1], c[2]);
    });
    perm_ = radixSortIndices(keys);
  }
  sorted_.resize(n);
  if (morton_order) parallelFor(std::int64_t(n), [&](std::int64_t s) { sorted_[std::size_t(s)] = points[std::size_t(perm_[std::size_t(s)])]; });
  const std::vector<Vec3<T>>& keyed = morton_order ? sorted_ : points;
  parallelFor(std::int64_t(n), [&](std::int64_t i) {
    std::int32_t c[3];
    cellOf(keyed[std::size_t(i)], c);
    keys[std::size_t(i)] = neighborBucket(p, c[0], c[1], c[2]);
  });
  if (morton_order) {
    countingSortByKey(keys, buckets, entries_, bucket_start_);
  } else {
    countingSortByKey(keys, buckets, perm_, bucket_start_);
    entries_.clear();
    parallelFor(std::int64_t(n), [&](std::int64_t s) { sorted_[std::size_t(s)] = points[std::size_t(perm_[std::size_t(s)])]; });
  }
  inv_perm_.resize(n);
  parallelFor(std::int64_t(n), [&](std::int64_t s) { inv_perm_[std::size_t(perm_[std::size_t(s)])] = std::int32_t(s); });
  slot_x_.resize(n);
  slot_y_.resize(n);
  slot_z_.resize(n);
  slot_orig_.resize(n);
  slot_store_.resize(n);
  parallelFor(std::int64_t(n), [&](std::int64_t e) {
    const std::size_t s = entries_.empty() ? std::size_t(e) : std::size_t(entries_[std::size_t(e)]);
    slot_x_[std::size_t(e)] = sorted_[s].x;
    slot_y_[std::size_t(e)] = sorted_[s].y;
    slot_z_[std::size_t(e)] = sorted_[s].z;
    slot_orig_[std::size_t(e)] = perm_[s];
    slot_store_[std::size_t(e)] = std::int32_t(s);
  });
}

template <typename T>
NeighborGridView<T> GridNeighborSearch<T>::view() const {
  NeighborGridView<T> g;
  g.p = params_;
  g.points = sorted_.data();
  g.bucket_start = bucket_start_.data();
  g.entries = entries_.empty() ? nullptr : entries_.data();
  g.n = std::int32_t(sorted_.size());
  return g;
}

template <typename T>
NeighborLists GridNeighborSearch<T>::querySelf(T radius) const {
  return run(nullptr, size(), std::vector<T>{radius}, true);
}

template <typename T>
NeighborLists GridNeighborSearch<T>::querySelf(const std::vector<T>& radii) const {
  return run(nullptr, size(), radii, true);
}

template <typename T>
NeighborLists GridNeighborSearch<T>::querySelfStorage(T radius) const {
  return run(nullptr, size(), std::vector<T>{radius}, true, true);
}

template <typename T>
NeighborLists GridNeighborSearch<T>::query(const std::vector<Vec3<T>>& queries, const std::vector<T>& radii) const {
  return run(queries.data(), queries.size(), radii, false);
}

template <typename T>
NeighborLists GridNeighborSearch<T>::query(const std::vector<Vec3<T>>& queries, T radius) const {
  return run(queries.data(), queries.size(), std::vector<T>{radius}, false);
}

template <typename T>
NeighborLists GridNeighborSearch<T>::run(const Vec3<T>* queries, std::size_t nq, const std::vector<T>& radii,
                                         bool self, bool storage) const {
  if (radii.size() != 1 && radii.size() != nq)
    throw InputError("", "radii", "expected 1 radius or one per query (" + std::to_string(nq) + "), got " +
                                      std::to_string(radii.size()));
  if (nq > kMaxPoints)
    throw InputError("", "queries", "too many queries (" + std::to_string(nq) + " > 2^30)");
  for (std::size_t i = 0; i < radii.size(); ++i)
    if (!neighborRadiusValid(radii[i]))
      throw InputError("", radii.size() == 1 ? std::string("radius") : "radii[" + std::to_string(i) + "]",
                       "must be finite and >= 0, got " + std::to_string(double(radii[i])));
  if (!self)
    for (std::size_t i = 0; i < nq; ++i)
      if (!neighborPointFinite(queries[i]))
        throw InputError("", "queries[" + std::to_string(i) + "]", "position " + describe(queries[i]) + " is not finite");

  const bool per_query = radii.size() == nq && nq > 1;
  const NeighborGridView<T> g = view();
  NeighborLists out;
  out.offsets.assign(nq + 1, 0);
  // One pass: each block of queries (in storage order for self-queries, for locality) appends its sorted
  // lists to its own buffer and records the counts; a prefix sum places the buffers. The GPU counts first
  // instead, because it cannot grow buffers; the lists are the same.
  const std::int64_t blocks = std::max<std::int64_t>(1, std::min<std::int64_t>(std::int64_t(nq), 4 * threadCount()));
  std::vector<std::vector<std::int32_t>> buffers(std::size_t(blocks), std::vector<std::int32_t>{});
  std::vector<char> out_of_memory(std::size_t(blocks), 0);  // exceptions must not leave the OpenMP region
  auto blockBegin = [&](std::int64_t b) { return std::size_t(b * std::int64_t(nq) / blocks); };
  parallelFor(blocks, [&](std::int64_t b) {
    std::vector<std::int32_t>& buf = buffers[std::size_t(b)];
    std::vector<std::int32_t> row;  // the dense fast path's candidates / hits of one query
    AppendIndex visit{&buf, storage ? nullptr : perm_.data()};
    // Storage-order lists name slots, original-order lists original indices (the fast path's id array).
    const std::int32_t* slot_ids = storage ? slot_store_.data() : slot_orig_.data();
    try {
      buf.reserve(std::size_t(blockBegin(b + 1) - blockBegin(b)) * 32);
      for (std::size_t i = blockBegin(b); i < blockBegin(b + 1); ++i) {
        const std::size_t q = self && !storage ? std::size_t(perm_[i]) : i;
        const Vec3<T>& x = self ? sorted_[i] : queries[i];
        const T r = per_query ? radii[q] : radii[0];
        const std::size_t first = buf.size();
        const DenseRowsResult fast =
            denseRows(g.p, g.bucket_start, slot_x_.data(), slot_y_.data(), slot_z_.data(), slot_ids, g.n,
                      x, r, self ? std::int32_t(q) : -1, row);
        if (fast.handled) {
          sortList(row.data(), fast.count);
          buf.insert(buf.end(), row.begin(), row.begin() + std::ptrdiff_t(fast.count));
        } else {
          forEachGridNeighbor(g, x, r, self ? std::int32_t(i) : -1, visit);
          sortList(buf.data() + first, buf.size() - first);
        }
        out.offsets[q + 1] = std::int64_t(buf.size() - first);
      }
    } catch (const std::bad_alloc&) {
      out_of_memory[std::size_t(b)] = 1;
      std::vector<std::int32_t>().swap(buf);
    }
  });
  bool failed = std::find(out_of_memory.begin(), out_of_memory.end(), 1) != out_of_memory.end();
  if (!failed) {
    for (std::size_t q = 0; q < nq; ++q) out.offsets[q + 1] += out.offsets[q];
    try {
      out.indices.resize(std::size_t(out.offsets[nq]));
    } catch (const std::bad_alloc&) {
      failed = true;
    }
  }
  if (failed)  // never truncate: either every list is complete or the caller gets an error
    throw InputError("", "radius", "the neighbour lists of " + std::to_string(nq) +
                                       " queries do not fit in memory; use a smaller radius");
  parallelFor(blocks, [&](std::int64_t b) {
    const std::int32_t* src = buffers[std::size_t(b)].data();
    for (std::size_t i = blockBegin(b); i < blockBegin(b + 1); ++i) {
      const std::size_t q = self && !storage ? std::size_t(perm_[i]) : i;
      const std::size_t k = std::size_t(out.offsets[q + 1] - out.offsets[q]);
      std::copy(src, src + k, out.indices.begin() + out.offsets[q]);
      src += k;
    }
  });
  return out;
}

template class GridNeighborSearch<float>;
template class GridNeighborSearch<double>;

}  // namespace inc::cpu
