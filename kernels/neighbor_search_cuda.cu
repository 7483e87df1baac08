// CUDA grid neighbour search: device bounding box, radix sort by cell, cell table, count / scan / fill of CSR lists.
#include "kernels/neighbor_search_cuda.h"

#include <cub/block/block_scan.cuh>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <cuda/atomic>
#include <cuda/std/functional>

#include <algorithm>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>

#include "kernels/cuda_check.h"
#include "kernels/graph_capture.h"
#include "model/input_error.h"

namespace inc::cuda {
namespace {

constexpr std::size_t kMaxPoints = std::size_t(1) << 30;  // same limit as the CPU search (int32 slots, 2^31 buckets)
constexpr int kThreads = 256;
constexpr int kReduceBlocks = 1024;  // bounding-box partials (stage 2 reduces them in one block)
constexpr std::uint64_t kNone = ~std::uint64_t(0);

unsigned blocksFor(std::size_t n) { return unsigned((n + kThreads - 1) / kThreads); }

template <typename T>
std::string describe(const Vec3<T>& x) {
  std::ostringstream s;
  s << "(" << x.x << ", " << x.y << ", " << x.z << ")";
  return s.str();
}

// Bits needed for keys in [0, count): the radix sort only looks at those.
int keyBits(std::uint64_t count) {
  int b = 1;
  while (b < 32 && (std::uint64_t(1) << b) < count) ++b;
  return b;
}

// ---- bounding box of the finite points and the first non-finite index (min/max are exact: deterministic) ----

template <typename T>
struct BoxAcc {
  T lo[3], hi[3];
  long long bad;
};

template <typename T>
__device__ void boxMerge(BoxAcc<T>& a, const BoxAcc<T>& b) {
  for (int k = 0; k < 3; ++k) {
    a.lo[k] = b.lo[k] < a.lo[k] ? b.lo[k] : a.lo[k];
    a.hi[k] = b.hi[k] > a.hi[k] ? b.hi[k] : a.hi[k];
  }
  a.bad = b.bad < a.bad ? b.bad : a.bad;
}

template <typename T>
__device__ BoxAcc<T> boxEmpty(long long n) {
  BoxAcc<T> a;
  for (int k = 0; k < 3; ++k) {
    a.lo[k] = std::numeric_limits<T>::max();
    a.hi[k] = std::numeric_limits<T>::lowest();
  }
  a.bad = n;
  return a;
}

// Tree reduction of one BoxAcc per thread in shared memory; thread 0 returns the block's result.
template <typename T>
__device__ BoxAcc<T> blockReduceBox(BoxAcc<T> a) {
  __shared__ T s_lo[3][kThreads], s_hi[3][kThreads];
  __shared__ long long s_bad[kThreads];
  const int t = threadIdx.x;
  for (int k = 0; k < 3; ++k) {
    s_lo[k][t] = a.lo[k];
    s_hi[k][t] = a.hi[k];
  }
  s_bad[t] = a.bad;
  __syncthreads();
  for (int stride = kThreads / 2; stride > 0; stride >>= 1) {
    if (t < stride) {
      BoxAcc<T> b;
      for (int k = 0; k < 3; ++k) {
        b.lo[k] = s_lo[k][t + stride];
        b.hi[k] = s_hi[k][t + stride];
      }
      b.bad = s_bad[t + stride];
      BoxAcc<T> c;
      for (int k = 0; k < 3; ++k) {
        c.lo[k] = s_lo[k][t];
        c.hi[k] = s_hi[k][t];
      }
      c.bad = s_bad[t];
      boxMerge(c, b);
      for (int k = 0; k < 3; ++k) {
        s_lo[k][t] = c.lo[k];
        s_hi[k][t] = c.hi[k];
      }
      s_bad[t] = c.bad;
    }
    __syncthreads();
  }
  BoxAcc<T> r;
  for (int k = 0; k < 3; ++k) {
    r.lo[k] = s_lo[k][0];
    r.hi[k] = s_hi[k][0];
  }
  r.bad = s_bad[0];
  return r;
}

template <typename T>
__global__ void boxPartialKernel(const Vec3<T>* pts, long long n, Vec3<T>* part_lo, Vec3<T>* part_hi,
                                 long long* part_bad) {
  BoxAcc<T> a = boxEmpty<T>(n);
  for (long long i = blockIdx.x * (long long)blockDim.x + threadIdx.x; i < n; i += (long long)gridDim.x * blockDim.x) {
    const Vec3<T> x = pts[i];
    if (!neighborPointFinite(x)) {
      a.bad = i < a.bad ? i : a.bad;
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      a.lo[k] = x[k] < a.lo[k] ? x[k] : a.lo[k];
      a.hi[k] = x[k] > a.hi[k] ? x[k] : a.hi[k];
    }
  }
  const BoxAcc<T> r = blockReduceBox(a);
  if (threadIdx.x == 0) {
    part_lo[blockIdx.x] = Vec3<T>(r.lo[0], r.lo[1], r.lo[2]);
    part_hi[blockIdx.x] = Vec3<T>(r.hi[0], r.hi[1], r.hi[2]);
    part_bad[blockIdx.x] = r.bad;
  }
}

// One block: merges the partials and makes the grid parameters (the host never needs the box itself), with
// the first non-finite point's value for the host's error message.
template <typename T>
__global__ void gridParamsKernel(const Vec3<T>* part_lo, const Vec3<T>* part_hi, const long long* part_bad, int parts,
                                 long long n, T cell_size, std::uint32_t bucket_count, const Vec3<T>* pts,
                                 GridParamsReadback<T>* out) {
  BoxAcc<T> a = boxEmpty<T>(n);
  for (int b = threadIdx.x; b < parts; b += blockDim.x) {
    BoxAcc<T> p;
    for (int k = 0; k < 3; ++k) {
      p.lo[k] = part_lo[b][k];
      p.hi[k] = part_hi[b][k];
    }
    p.bad = part_bad[b];
    boxMerge(a, p);
  }
  const BoxAcc<T> r = blockReduceBox(a);
  if (threadIdx.x == 0) {
    const bool any_finite = r.lo[0] <= r.hi[0];
    const Vec3<T> lo = any_finite ? Vec3<T>(r.lo[0], r.lo[1], r.lo[2]) : Vec3<T>();
    const Vec3<T> hi = any_finite ? Vec3<T>(r.hi[0], r.hi[1], r.hi[2]) : Vec3<T>();
    out->p = makeNeighborGridParams(lo, hi, cell_size, bucket_count, std::int64_t(r.bad), any_finite);
    out->bad = r.bad < n ? pts[r.bad] : Vec3<T>();
  }
}

// ---- keys, sort, cell table ----

template <typename T>
__device__ void cellOf(const NeighborGridParams<T>& p, const Vec3<T>& x, std::int32_t c[3]) {
  for (int a = 0; a < 3; ++a) c[a] = neighborCellCoord(x[a], p.origin[a], neighborInvCell(p, a));
}

// keys[i] = bucket of pts[i] (counted into the histogram) or its Morton key.
// The parameters come from device memory (the host has not read them). A non-finite point (the build is
// rejected when the host reads the parameters) gets cell (0, 0, 0): every key stays inside the table.
template <typename T>
__global__ void cellKeysKernel(const GridParamsReadback<T>* params, const Vec3<T>* pts, int n, bool morton,
                               std::uint32_t* keys, std::int32_t* histogram) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const NeighborGridParams<T> p = params->p;
  const Vec3<T> x = pts[i];
  std::int32_t c[3] = {0, 0, 0};
  if (neighborPointFinite(x)) cellOf(p, x, c);
  if (morton) {
    keys[i] = neighborMortonKey(p, c[0], c[1], c[2]);
  } else {
    const std::uint32_t b = neighborBucket(p, c[0], c[1], c[2]);
    keys[i] = b;
    atomicAdd(histogram + b, 1);  // integer counts: the result does not depend on the order
  }
}

// values[i] = i: the sort's values (written once per size, not per build: the sorts only read them).
__global__ void iotaKernel(int n, std::int32_t* values) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) values[i] = i;
}

// The coordinates the query kernels read: float points as float4 (one 16-byte load per candidate instead of
// three 4-byte ones; w unused), double points as they are.
template <typename T>
struct PackedPoint {
  using type = Vec3<T>;
};
template <>
struct PackedPoint<float> {
  using type = float4;
};

__device__ inline Vec3<float> unpackPoint(const float4* p, std::int32_t j) {
  const float4 v = __ldg(p + j);
  return Vec3<float>(v.x, v.y, v.z);
}
__device__ inline Vec3<double> unpackPoint(const Vec3<double>* p, std::int32_t j) { return p[j]; }

__device__ inline void packPoint(float4* p, int s, const Vec3<float>& x) { p[s] = make_float4(x.x, x.y, x.z, 0.0f); }
__device__ inline void packPoint(Vec3<double>*, int, const Vec3<double>&) {}  // doubles are read from `sorted`

// The grid as the kernels see it: NeighborGridView's members, points read from the packed copy.
template <typename T>
struct DeviceGridView {
  NeighborGridParams<T> p;
  const typename PackedPoint<T>::type* points;
  const std::int32_t* bucket_start;
  const std::int32_t* entries;
  std::int32_t n;
  __device__ Vec3<T> point(std::int32_t j) const { return unpackPoint(points, j); }
};

// sorted[s] = pts[perm[s]] and/or its packed copy (whichever is not null).
template <typename T>
__global__ void gatherKernel(const Vec3<T>* pts, const std::int32_t* perm, int n, Vec3<T>* sorted,
                             typename PackedPoint<T>::type* packed) {
  const int s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= n) return;
  const Vec3<T> x = pts[perm[s]];
  if (sorted) sorted[s] = x;
  if (packed) packPoint(packed, s, x);
}

// inv[perm[s]] = s.
__global__ void invertKernel(const std::int32_t* perm, int n, std::int32_t* inv) {
  const int s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s < n) inv[perm[s]] = s;
}

__global__ void unpackKernel(const float4* packed, int n, Vec3<float>* out) {
  const int s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s < n) out[s] = unpackPoint(packed, s);
}

// ---- queries ----

// First invalid query point and radius (atomicMin on integers: the smallest index wins whatever the order).
template <typename T>
__global__ void validateKernel(const Vec3<T>* queries, long long nq, const T* radii, long long nr,
                               unsigned long long* status) {
  const long long i = blockIdx.x * (long long)blockDim.x + threadIdx.x;
  if (queries && i < nq && !neighborPointFinite(queries[i])) atomicMin(status + 0, (unsigned long long)i);
  if (radii && i < nr && !neighborRadiusValid(radii[i])) atomicMin(status + 1, (unsigned long long)i);
}

struct CountVisit {
  std::int32_t k;
  __host__ __device__ void operator()(std::int32_t) { ++k; }
};

struct WriteVisit {
  std::int32_t* row;
  const std::int32_t* perm;
  std::int32_t k;
  __host__ __device__ void operator()(std::int32_t j) { row[k++] = perm[j]; }
};

// Which point and radius thread t handles: self-queries run in storage order (neighbouring threads read
// neighbouring cells) and write to the query's original index.
template <typename T>
struct QuerySpec {
  DeviceGridView<T> g;
  const Vec3<T>* queries;  // nullptr: self-query
  const std::int32_t* perm;
  const T* radii;  // nullptr: `radius` for all; else radii[q * radii_stride]
  int radii_stride;
  T radius;
  int nq;
};

template <typename T>
__device__ void queryOf(const QuerySpec<T>& s, int t, int& q, Vec3<T>& x, T& r, std::int32_t& skip) {
  if (s.queries) {
    q = t;
    x = s.queries[t];
    skip = -1;
  } else {
    q = s.perm[t];
    x = s.g.point(t);
    skip = t;
  }
  r = s.radii ? s.radii[q * s.radii_stride] : s.radius;
}

template <typename T>
__global__ void countKernel(QuerySpec<T> s, std::int32_t* counts) {
  const int t = blockIdx.x * blockDim.x + threadIdx.x;
  if (t >= s.nq) return;
  int q;
  Vec3<T> x;
  T r;
  std::int32_t skip;
  queryOf(s, t, q, x, r, skip);
  CountVisit v{0};
  forEachGridNeighbor(s.g, x, r, skip, v);
  counts[q] = v.k;
}

__global__ void totalKernel(const std::int64_t* offsets, std::size_t nq, unsigned long long* status) {
  if (blockIdx.x == 0 && threadIdx.x == 0) status[2] = (unsigned long long)offsets[nq];
}

// In-place ascending sort of one row: insertion sort for the usual short rows, heap sort (O(k log k), no extra
// memory) for long ones. Indices in a row are distinct, so any correct sort gives the CPU's order.
__device__ void sortRow(std::int32_t* a, std::int32_t k) {
  if (k <= 32) {
    for (std::int32_t i = 1; i < k; ++i) {
      const std::int32_t v = a[i];
      std::int32_t j = i;
      for (; j > 0 && a[j - 1] > v; --j) a[j] = a[j - 1];
      a[j] = v;
    }
    return;
  }
  auto siftDown = [a](std::int32_t root, std::int32_t end) {
    while (2 * root + 1 < end) {
      std::int32_t child = 2 * root + 1;
      if (child + 1 < end && a[child] < a[child + 1]) ++child;
      if (!(a[root] < a[child])) return;
      const std::int32_t tmp = a[root];
      a[root] = a[child];
      a[child] = tmp;
      root = child;
    }
  };
  for (std::int32_t start = k / 2 - 1; start >= 0; --start) siftDown(start, k);
  for (std::int32_t end = k - 1; end > 0; --end) {
    const std::int32_t tmp = a[0];
    a[0] = a[end];
    a[end] = tmp;
    siftDown(0, end);
  }
}

// Rows of at most kRowCap entries (the usual case: ~30 neighbours) are built in shared memory (appended
// during the traversal, sorted after it), and written out by the whole warp, one row after another,
// so that the global writes are coalesced. Longer rows (the count pass says which) take the old path:
// written to global memory in traversal order, then sorted there (heap sort above 32 entries).
constexpr int kFillThreads = 128;
constexpr int kRowCap = 48;
constexpr int kRowStride = kFillThreads + 1;  // odd stride: the warp's column reads hit 32 distinct banks
// The storage-order kernel keeps rows of at most 40 in shared memory and is held to 48 registers, so that ten
// 128-thread tiles fit an SM instead of eight (shared memory and registers both limited it). Measured on an
// H100 (docs/neighbor-search.md): 1e6 points 0.440 -> 0.420 ms, 1.6e7 6.25 -> 5.71 ms for the traversal; a cap of
// 32 (twelve tiles) sends too many rows of the ~28-neighbour lattice down the long-row path (0.66 ms).
constexpr int kStorageRowCap = 40;
constexpr int kStorageMinBlocks = 10;

// Appends during the traversal (a store and an increment: lanes of a warp hit at different candidates, so
// whatever the visitor does runs for the whole warp at almost every candidate), sorts once afterwards.
// The storage index is kept; finishColumn maps it to the original index after the loop.
template <int Cap>
struct SharedAppendVisitT {
  std::int32_t* col;  // this thread's column: entry i at col[i * kRowStride]
  std::int32_t k;
  __device__ void operator()(std::int32_t j) {
    // Beyond Cap entries the row is only counted (the caller then rebuilds it in global memory).
    if (k < Cap) col[k * kRowStride] = j;
    ++k;
  }
};
using SharedAppendVisit = SharedAppendVisitT<kRowCap>;

// Insertion sort of a column of k <= kRowCap entries in shared memory (linear when it is already sorted, as
// storage-order rows of a dense grid in bucket order are).
__device__ void sortColumn(std::int32_t* col, std::int32_t k) {
  for (std::int32_t i = 1; i < k; ++i) {
    const std::int32_t v = col[i * kRowStride];
    std::int32_t j = i;
    for (; j > 0; --j) {
      const std::int32_t u = col[(j - 1) * kRowStride];
      if (u <= v) break;
      col[j * kRowStride] = u;
    }
    col[j * kRowStride] = v;
  }
}

// Maps a column of k <= kRowCap storage indices to original indices and sorts it.
__device__ void finishColumn(std::int32_t* col, std::int32_t k, const std::int32_t* perm) {
  for (std::int32_t i = 0; i < k; ++i) col[i * kRowStride] = perm[col[i * kRowStride]];
  sortColumn(col, k);
}

// Fused first pass: one traversal per query counts its neighbours (counts[q]) and, for rows of at most
// kRowCap entries, leaves the sorted row in staged[t * kRowCap ...] (t = the thread's storage slot, so a
// warp writes one contiguous block). Longer rows are only counted; fillKernel rebuilds them.
template <typename T>
__global__ void __launch_bounds__(kFillThreads)
    countStageKernel(QuerySpec<T> s, std::int32_t* counts, std::int32_t* staged) {
  __shared__ std::int32_t buf[kRowCap * kRowStride];
  const int t = blockIdx.x * blockDim.x + threadIdx.x;
  std::int32_t small_k = 0;
  if (t < s.nq) {  // no early return: the whole warp takes part in the write-out below
    int q;
    Vec3<T> x;
    T r;
    std::int32_t skip;
    queryOf(s, t, q, x, r, skip);
    SharedAppendVisit v{buf + threadIdx.x, 0};
    forEachGridNeighbor(s.g, x, r, skip, v);
    counts[q] = v.k;
    small_k = v.k <= kRowCap ? v.k : 0;
    finishColumn(buf + threadIdx.x, small_k, s.perm);
  }
  __syncwarp();
  const int lane = threadIdx.x & 31;
  const int warp_base = threadIdx.x & ~31;
  const std::int64_t slot0 = std::int64_t(blockIdx.x) * blockDim.x + warp_base;
  for (int l = 0; l < 32; ++l) {
    const std::int32_t kk = __shfl_sync(0xffffffffu, small_k, l);
    const std::int32_t* col = buf + warp_base + l;
    std::int32_t* dst = staged + (slot0 + l) * kRowCap;
    for (std::int32_t i = lane; i < kk; i += 32) dst[i] = col[i * kRowStride];
  }
}

// Second pass. staged == nullptr (two-pass mode, after countKernel): traverse again, building rows of at
// most kRowCap entries sorted in shared memory. staged != nullptr (after countStageKernel): rows of at most
// kRowCap entries are copied from staged. Either way rows are written by the whole warp (coalesced), and
// longer rows are traversed again into global memory and sorted there.
template <typename T>
__global__ void __launch_bounds__(kFillThreads)
    fillKernel(QuerySpec<T> s, const std::int64_t* offsets, const std::int32_t* staged, std::int32_t* indices) {
  __shared__ std::int32_t buf[kRowCap * kRowStride];
  const int t = blockIdx.x * blockDim.x + threadIdx.x;
  const bool active = t < s.nq;  // no early return: the whole warp takes part in the write-out below
  std::int64_t begin = 0;
  std::int32_t small_k = 0;
  if (active) {
    int q;
    Vec3<T> x;
    T r;
    std::int32_t skip;
    queryOf(s, t, q, x, r, skip);
    begin = offsets[q];
    const std::int64_t k = offsets[q + 1] - begin;
    if (k <= kRowCap) {
      if (!staged) {
        SharedAppendVisit v{buf + threadIdx.x, 0};
        forEachGridNeighbor(s.g, x, r, skip, v);
        finishColumn(buf + threadIdx.x, v.k <= kRowCap ? v.k : 0, s.perm);  // v.k == k <= kRowCap (same traversal)
      }
      small_k = std::int32_t(k);
    } else {
      WriteVisit v{indices + begin, s.perm, 0};
      forEachGridNeighbor(s.g, x, r, skip, v);
      sortRow(v.row, v.k);
    }
  }
  __syncwarp();
  const int lane = threadIdx.x & 31;
  const int warp_base = threadIdx.x & ~31;
  const std::int64_t slot0 = std::int64_t(blockIdx.x) * blockDim.x + warp_base;
  for (int l = 0; l < 32; ++l) {
    const std::int64_t b = __shfl_sync(0xffffffffu, begin, l);
    const std::int32_t kk = __shfl_sync(0xffffffffu, small_k, l);
    if (staged) {
      const std::int32_t* src = staged + (slot0 + l) * kRowCap;
      for (std::int32_t i = lane; i < kk; i += 32) indices[b + i] = src[i];
    } else {
      const std::int32_t* col = buf + warp_base + l;
      for (std::int32_t i = lane; i < kk; i += 32) indices[b + i] = col[i * kRowStride];
    }
  }
}

// ---- storage-order self-query: one traversal, rows written in place (decoupled look-back) ----

// Tile status words of the look-back scan (Merrill & Garland 2016): a 2-bit flag over a 62-bit count.
constexpr std::uint64_t kTileAggregate = std::uint64_t(1) << 62;  // the tile's own total is published
constexpr std::uint64_t kTileInclusive = std::uint64_t(2) << 62;  // the total of tiles 0..this is published
constexpr std::uint64_t kTileValue = (std::uint64_t(1) << 62) - 1;

__device__ inline std::uint64_t tileLoad(std::uint64_t* w) {
  return ::cuda::atomic_ref<std::uint64_t, ::cuda::thread_scope_device>(*w).load(::cuda::memory_order_acquire);
}
__device__ inline void tileStore(std::uint64_t* w, std::uint64_t v) {
  ::cuda::atomic_ref<std::uint64_t, ::cuda::thread_scope_device>(*w).store(v, ::cuda::memory_order_release);
}

// Called by the 32 lanes of a tile's first warp: publishes the tile's aggregate, sums the predecessors'
// published values 32 at a time back to the nearest inclusive prefix, publishes this tile's inclusive prefix
// and returns the exclusive one. Tiles take their index from an atomic counter in launch order, so every
// predecessor is already running: the wait always ends.
__device__ std::uint64_t tileExclusivePrefix(std::uint64_t* status, int tile, std::uint64_t aggregate) {
  const int lane = threadIdx.x & 31;
  if (tile == 0) {
    if (lane == 0) tileStore(status, kTileInclusive | aggregate);
    return 0;
  }
  if (lane == 0) tileStore(status + tile, kTileAggregate | aggregate);
  std::uint64_t exclusive = 0;
  for (int end = tile - 1;; end -= 32) {
    const int p = end - lane;  // lane 0 looks at the nearest predecessor
    std::uint64_t w = p >= 0 ? tileLoad(status + p) : kTileInclusive;
    while (__any_sync(0xffffffffu, (w >> 62) == 0))
      if ((w >> 62) == 0) w = tileLoad(status + p);
    const unsigned inclusive = __ballot_sync(0xffffffffu, (w >> 62) == 2);
    const int stop = inclusive ? __ffs(int(inclusive)) - 1 : 31;  // nearest inclusive prefix, else the window
    std::uint64_t v = lane <= stop ? (w & kTileValue) : 0;
    for (int o = 16; o > 0; o >>= 1) v += __shfl_down_sync(0xffffffffu, v, o);
    exclusive += __shfl_sync(0xffffffffu, v, 0);
    if (inclusive) break;
  }
  if (lane == 0) tileStore(status + tile, kTileInclusive | (exclusive + aggregate));
  return exclusive;
}

struct SlotWriteVisit {
  std::int32_t* row;
  std::int32_t k;
  __device__ void operator()(std::int32_t j) { row[k++] = j; }
};

// Storage-order self-query in one pass. Tile = kFillThreads consecutive storage slots. Each thread traverses
// its slot's neighbourhood into a shared-memory column (rows of at most kRowCap; longer ones are counted),
// the tile scans its counts, the look-back gives the tile's offset, and the rows are written straight to
// their CSR place by the whole warp (consecutive rows are contiguous: coalesced). Rows are only written when
// the whole list fits `capacity` (the host checks offsets[nq] and runs again with an exact buffer if not);
// the offsets are always complete. tile_status has gridDim.x zeroed words plus the tile counter.
template <typename T, int Cap = kRowCap, int MinBlocks = 1>
__global__ void __launch_bounds__(kFillThreads, MinBlocks)
    storageSelfKernel(QuerySpec<T> s, std::int64_t* offsets, std::int32_t* indices, std::uint64_t capacity,
                      std::uint64_t* tile_status) {
  using Scan = cub::BlockScan<std::uint64_t, kFillThreads>;
  __shared__ std::int32_t buf[Cap * kRowStride];
  __shared__ typename Scan::TempStorage scan_tmp;
  __shared__ int s_tile;
  __shared__ std::uint64_t s_prefix;
  if (threadIdx.x == 0) s_tile = int(atomicAdd(reinterpret_cast<unsigned long long*>(tile_status + gridDim.x), 1ull));
  __syncthreads();
  const int tile = s_tile;
  const int t = tile * kFillThreads + int(threadIdx.x);
  const bool active = t < s.nq;
  std::int32_t k = 0;
  Vec3<T> x;
  if (active) {
    x = s.g.point(t);
    SharedAppendVisitT<Cap> v{buf + threadIdx.x, 0};
    forEachGridNeighbor(s.g, x, s.radius, t, v);
    k = v.k;
    if (k <= Cap) sortColumn(buf + threadIdx.x, k);
  }
  std::uint64_t local = 0, tile_total = 0;
  Scan(scan_tmp).ExclusiveSum(std::uint64_t(k), local, tile_total);
  if (threadIdx.x < 32) {
    const std::uint64_t prefix = tileExclusivePrefix(tile_status, tile, tile_total);
    if (threadIdx.x == 0) s_prefix = prefix;
  }
  __syncthreads();
  const std::uint64_t begin = s_prefix + local;
  const bool fits = begin + std::uint64_t(k) <= capacity;
  if (active) {
    offsets[t] = std::int64_t(begin);
    if (t == s.nq - 1) offsets[s.nq] = std::int64_t(begin + std::uint64_t(k));
    if (k > Cap && fits) {  // a long row: traverse again straight into its place, then sort it there
      SlotWriteVisit v{indices + begin, 0};
      forEachGridNeighbor(s.g, x, s.radius, t, v);
      sortRow(v.row, v.k);
    }
  }
  const std::int32_t small_k = active && fits && k <= Cap ? k : 0;
  __syncwarp();
  const int lane = threadIdx.x & 31;
  const int warp_base = threadIdx.x & ~31;
  for (int l = 0; l < 32; ++l) {
    const std::uint64_t b = __shfl_sync(0xffffffffu, begin, l);
    const std::int32_t kk = __shfl_sync(0xffffffffu, small_k, l);
    const std::int32_t* col = buf + warp_base + l;
    for (std::int32_t i = lane; i < kk; i += 32) indices[b + std::uint64_t(i)] = col[i * kRowStride];
  }
}

// The grid part of a query's parameters (queries, radii and count are the caller's).
template <typename T>
QuerySpec<T> querySpec(const NeighborGridParams<T>& params, const Packed4<T>* packed, const Vec3<T>* sorted,
                       const std::int32_t* bucket_start, const std::int32_t* entries, const std::int32_t* perm,
                       std::size_t n) {
  QuerySpec<T> s{};
  s.g.p = params;
  if constexpr (std::is_same_v<T, float>)
    s.g.points = reinterpret_cast<const float4*>(packed);
  else
    s.g.points = sorted;
  s.g.bucket_start = bucket_start;
  s.g.entries = entries;
  s.g.n = std::int32_t(n);
  s.perm = perm;
  return s;
}

template <typename T>
void checkCellSize(T h) {
  if (!(h > T(0)) || !neighborRadiusValid(h) || !neighborRadiusValid(T(1) / h))
    throw InputError("", "cell_size", "must be finite and > 0 with a finite inverse, got " + std::to_string(double(h)));
}

}  // namespace

NeighborLists DeviceNeighborLists::download() const {
  NeighborLists l;
  l.offsets = offsets.download();
  l.indices = indices.download();
  if (l.offsets.empty()) l.offsets.assign(1, 0);
  return l;
}

template <typename T>
void GridNeighborSearch<T>::mark(const char* stage) const {
  if (!profiling_) return;
  cudaEvent_t e = nullptr;
  INC_CUDA(cudaEventCreate(&e));
  marks_.emplace_back(stage, std::shared_ptr<void>(e, [](void* p) { cudaEventDestroy(static_cast<cudaEvent_t>(p)); }));
  INC_CUDA(cudaEventRecord(e));
}

template <typename T>
std::vector<std::pair<std::string, double>> GridNeighborSearch<T>::takeProfile() const {
  std::vector<std::pair<std::string, double>> r;
  if (marks_.size() >= 2) {
    INC_CUDA(cudaEventSynchronize(static_cast<cudaEvent_t>(marks_.back().second.get())));
    for (std::size_t i = 1; i < marks_.size(); ++i) {
      float ms = 0.0f;
      INC_CUDA(cudaEventElapsedTime(&ms, static_cast<cudaEvent_t>(marks_[i - 1].second.get()),
                                    static_cast<cudaEvent_t>(marks_[i].second.get())));
      r.emplace_back(marks_[i].first, double(ms));
    }
  }
  marks_.clear();
  return r;
}

template <typename T>
void* GridNeighborSearch<T>::scratch(std::size_t bytes) const {
  temp_.resize(bytes == 0 ? 1 : bytes);
  return temp_.data();
}

template <typename T>
void GridNeighborSearch<T>::build(const std::vector<Vec3<T>>& points, T cell_size, bool morton_order) {
  upload_.upload(points);
  build(upload_.data(), points.size(), cell_size, morton_order);
  ensureParams();
}

template <typename T>
const std::int32_t* GridNeighborSearch<T>::originalToSorted() const {
  ensureParams();
  if (!inverse_ready_ && n_ > 0) {
    inv_perm_.resize(n_);
    invertKernel<<<blocksFor(n_), kThreads>>>(perm_.data(), int(n_), inv_perm_.data());
    INC_CUDA_LAUNCH("invertKernel");
  }
  inverse_ready_ = true;
  return inv_perm_.data();
}

template <typename T>
const Vec3<T>* GridNeighborSearch<T>::sortedPoints() const {
  ensureParams();
  if constexpr (std::is_same_v<T, float>) {
    if (!sorted_ready_ && n_ > 0) {
      sorted_.resize(n_);
      unpackKernel<<<blocksFor(n_), kThreads>>>(reinterpret_cast<const float4*>(packed_.data()), int(n_),
                                                sorted_.data());
      INC_CUDA_LAUNCH("unpackKernel");
    }
  }
  sorted_ready_ = true;
  return sorted_.data();
}

template <typename T>
void GridNeighborSearch<T>::ensureParams() const {
  if (pending_n_ == 0) return;
  INC_CUDA(cudaEventSynchronize(static_cast<cudaEvent_t>(params_event_.get())));
  const GridParamsReadback<T> rb = *static_cast<const GridParamsReadback<T>*>(pinned_params_.get());
  const std::size_t n = pending_n_;
  pending_n_ = 0;
  params_ = rb.p;
  if (params_.first_bad < std::int64_t(n)) {  // the grid is empty from here on: nothing may use it
    n_ = 0;
    used_buckets_ = 0;
    const std::string i = std::to_string(params_.first_bad);
    throw InputError("", "points[" + i + "]", "position " + describe(rb.bad) + " is not finite");
  }
  std::uint64_t used = std::uint64_t(params_.bucket_mask) + 1;
  if (params_.dense)
    used = std::uint64_t(params_.dims[0]) * std::uint64_t(params_.dims[1]) * std::uint64_t(params_.dims[2]);
  used_buckets_ = std::size_t(used);
  n_ = n;
}

template <typename T>
void GridNeighborSearch<T>::build(const Vec3<T>* d_points, std::size_t n, T cell_size, bool morton_order) {
  checkCellSize(cell_size);
  if (n > kMaxPoints)
    throw InputError("", "points", "too many points for the grid search (" + std::to_string(n) + " > 2^30)");
  if (n > 0 && !d_points) throw InputError("", "points", "null device pointer for " + std::to_string(n) + " points");
  cell_size_ = cell_size;
  morton_ = morton_order;
  n_ = 0;
  pending_n_ = 0;
  // The Vec3 copy is written by the build for double (its queries read it) and by a Morton build (its bucket
  // keys are computed from it); float bucket-order builds make it on request.
  sorted_ready_ = !std::is_same_v<T, float> || morton_order;
  inverse_ready_ = false;
  const std::uint32_t buckets = neighborBucketCount(n);
  if (n == 0) {
    params_ = makeNeighborGridParams(Vec3<T>(), Vec3<T>(), cell_size, buckets, 0, false);
    used_buckets_ = 0;
    return;
  }
  // Everything a build touches is sized from n alone (below), so the whole build is enqueued without reading
  // anything back. Sized without the grid parameters: a dense grid has at most `buckets` cells
  // (makeNeighborGridParams), a hashed one exactly `buckets` buckets, so a cell table and a key width for
  // `buckets` hold either. Buckets past a dense grid's cells stay empty (their start is n); no query visits them.
  const int parts = int(std::min<std::size_t>(kReduceBlocks, blocksFor(n)));
  partial_lo_.resize(std::size_t(parts));
  partial_hi_.resize(std::size_t(parts));
  partial_bad_.resize(std::size_t(parts));
  d_params_.resize(1);
  sorted_.resize(n);
  if constexpr (std::is_same_v<T, float>) packed_.resize(n);
  perm_.resize(n);
  keys_.resize(n);
  keys_sorted_.resize(n);
  if (iota_.size() < n || iota_.data() != iota_for_) {
    iota_.resize(std::max(n, iota_.size()));
    iotaKernel<<<blocksFor(iota_.size()), kThreads>>>(int(iota_.size()), iota_.data());
    INC_CUDA_LAUNCH("iotaKernel");
    iota_for_ = iota_.data();
  }
  if (morton_order) entries_.resize(n);
  used_buckets_ = buckets;
  cell_count_.resize(std::size_t(buckets) + 1);
  bucket_start_.resize(std::size_t(buckets) + 1);
  if (!pinned_params_) {
    void* h = nullptr;
    INC_CUDA(cudaMallocHost(&h, sizeof(GridParamsReadback<T>)));
    pinned_params_ = std::shared_ptr<void>(h, [](void* q) { cudaFreeHost(q); });
    cudaEvent_t e = nullptr;
    INC_CUDA(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
    params_event_ = std::shared_ptr<void>(e, [](void* q) { cudaEventDestroy(static_cast<cudaEvent_t>(q)); });
    cudaStream_t st = nullptr;
    // A blocking stream: ordered after the caller's work on the legacy default stream (the points' upload)
    // and before later work there (the queries), as if everything ran on the default stream.
    INC_CUDA(cudaStreamCreate(&st));
    stream_ = std::shared_ptr<void>(st, [](void* q) { cudaStreamDestroy(static_cast<cudaStream_t>(q)); });
    // The read-back's own branch (fork after the parameters, join at the end of the build), so that the copy
    // is not on the build's critical path.
    INC_CUDA(cudaStreamCreateWithFlags(&st, cudaStreamNonBlocking));
    side_stream_ = std::shared_ptr<void>(st, [](void* q) { cudaStreamDestroy(static_cast<cudaStream_t>(q)); });
    for (std::shared_ptr<void>* ev : {&fork_event_, &join_event_}) {
      INC_CUDA(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
      *ev = std::shared_ptr<void>(e, [](void* q) { cudaEventDestroy(static_cast<cudaEvent_t>(q)); });
    }
  }
  // CUB's scratch for the largest sort and the scan, allocated before anything is enqueued (no allocation may
  // happen inside a graph capture).
  {
    std::size_t sort_bytes = 0, scan_bytes = 0;
    INC_CUDA(cub::DeviceRadixSort::SortPairs(nullptr, sort_bytes, keys_.data(), keys_sorted_.data(), iota_.data(),
                                             perm_.data(), int(n), 0, 30));
    INC_CUDA(cub::DeviceScan::ExclusiveScan(nullptr, scan_bytes, cell_count_.data(), bucket_start_.data(),
                                            ::cuda::std::plus<std::int32_t>{}, std::int32_t(0),
                                            std::size_t(buckets) + 1));
    scratch(std::max(sort_bytes, scan_bytes));
  }
  cudaStream_t st = static_cast<cudaStream_t>(stream_.get());
  if (morton_order || profiling_) {
    // Morton order waits for the parameters inside the build (its key width depends on the grid's extent);
    // profiling records events between the stages: both run the stages directly.
    enqueueBuild(d_points, n, buckets, st);
  } else {
    // The same stages as one CUDA graph: launched in one call instead of a dozen launches and CUB calls,
    // re-captured only when the inputs or a buffer change.
    const BuildGraphKey key{{d_points, sorted_.data(), packed_.data(), perm_.data(), keys_.data(), keys_sorted_.data(),
                             iota_.data(), cell_count_.data(), bucket_start_.data(), temp_.data(), d_params_.data(),
                             partial_lo_.data(), partial_hi_.data(), partial_bad_.data(), pinned_params_.get()},
                            n,
                            cell_size};
    if (!build_graph_ || !(key == build_key_)) {
      build_graph_.reset();
      cudaGraphExec_t exec = nullptr;
      captureGraph(st, exec, [&] { enqueueBuild(d_points, n, buckets, st); });
      build_graph_ =
          std::shared_ptr<void>(exec, [](void* q) { cudaGraphExecDestroy(static_cast<cudaGraphExec_t>(q)); });
      build_key_ = key;
    }
    INC_CUDA(cudaGraphLaunch(static_cast<cudaGraphExec_t>(build_graph_.get()), st));
  }
  pending_n_ = n;
}

// The stages of a build on `st` (recorded into the build graph, or run directly): no host synchronisation
// except Morton order's wait for the parameters.
template <typename T>
void GridNeighborSearch<T>::enqueueBuild(const Vec3<T>* d_points, std::size_t n, std::uint32_t buckets,
                                         cudaStream_t st) {
  const int ni = int(n);
  const std::size_t table = std::size_t(buckets) + 1;
  mark("build:start");
  // 1. Bounding box and first non-finite point, reduced on the device into the grid parameters, which go
  // back to the host asynchronously (page-locked buffer + event, an event node in the graph); the host reads
  // them in ensureParams when it first needs them.
  const int parts = int(partial_lo_.size());
  boxPartialKernel<T><<<parts, kThreads, 0, st>>>(d_points, (long long)n, partial_lo_.data(), partial_hi_.data(),
                                                  reinterpret_cast<long long*>(partial_bad_.data()));
  INC_CUDA_LAUNCH("boxPartialKernel");
  gridParamsKernel<T><<<1, kThreads, 0, st>>>(partial_lo_.data(), partial_hi_.data(),
                                              reinterpret_cast<const long long*>(partial_bad_.data()), parts,
                                              (long long)n, cell_size_, buckets, d_points, d_params_.data());
  INC_CUDA_LAUNCH("gridParamsKernel");
  cudaStream_t side = static_cast<cudaStream_t>(side_stream_.get());
  cudaEvent_t fork = static_cast<cudaEvent_t>(fork_event_.get()), join = static_cast<cudaEvent_t>(join_event_.get());
  cudaStreamCaptureStatus capturing = cudaStreamCaptureStatusNone;
  INC_CUDA(cudaStreamIsCapturing(st, &capturing));
  INC_CUDA(cudaEventRecord(fork, st));
  INC_CUDA(cudaStreamWaitEvent(side, fork, 0));
  INC_CUDA(cudaMemcpyAsync(pinned_params_.get(), d_params_.data(), sizeof(GridParamsReadback<T>),
                           cudaMemcpyDeviceToHost, side));
  // Inside a capture the record becomes an event node (recorded at every replay); outside, a plain record.
  if (capturing == cudaStreamCaptureStatusActive)
    INC_CUDA(cudaEventRecordWithFlags(static_cast<cudaEvent_t>(params_event_.get()), side, cudaEventRecordExternal));
  else
    INC_CUDA(cudaEventRecord(static_cast<cudaEvent_t>(params_event_.get()), side));
  INC_CUDA(cudaEventRecord(join, side));
  mark("build:box+params");
  const int bucket_bits = keyBits(buckets);
  typename PackedPoint<T>::type* packed = nullptr;
  if constexpr (std::is_same_v<T, float>) packed = reinterpret_cast<float4*>(packed_.data());
  INC_CUDA(cudaMemsetAsync(cell_count_.data(), 0, table * sizeof(std::int32_t), st));

  auto radixSort = [&](const std::uint32_t* keys_in, std::uint32_t* keys_out, const std::int32_t* vals_in,
                       std::int32_t* vals_out, int bits) {
    std::size_t bytes = temp_.size();
    INC_CUDA(
        cub::DeviceRadixSort::SortPairs(temp_.data(), bytes, keys_in, keys_out, vals_in, vals_out, ni, 0, bits, st));
  };

  // 2. Storage order. CUB's radix sort is stable, like the CPU's counting sort, so slots agree exactly.
  const Vec3<T>* keyed = d_points;
  if (morton_) {
    // The Z-order key width depends on the grid's extent: the one host wait of a Morton build (and the
    // non-finite check, so a Morton build reports a bad point here).
    pending_n_ = n;
    ensureParams();
    n_ = 0;  // the build is not finished: the grid stays unusable until its end
    cellKeysKernel<T><<<blocksFor(n), kThreads, 0, st>>>(d_params_.data(), d_points, ni, true, keys_.data(), nullptr);
    INC_CUDA_LAUNCH("cellKeysKernel(morton)");
    const int max_dim = std::max(params_.dims[0], std::max(params_.dims[1], params_.dims[2]));
    const int axis_bits = keyBits(std::uint64_t(max_dim)) - params_.morton_shift;
    radixSort(keys_.data(), keys_sorted_.data(), iota_.data(), perm_.data(), std::max(1, std::min(30, 3 * axis_bits)));
    gatherKernel<T><<<blocksFor(n), kThreads, 0, st>>>(d_points, perm_.data(), ni, sorted_.data(), packed);
    INC_CUDA_LAUNCH("gatherKernel(morton)");
    keyed = sorted_.data();
    mark("build:morton keys+sort+gather");
  }
  cellKeysKernel<T>
      <<<blocksFor(n), kThreads, 0, st>>>(d_params_.data(), keyed, ni, false, keys_.data(), cell_count_.data());
  INC_CUDA_LAUNCH("cellKeysKernel(bucket)");
  mark("build:bucket keys+histogram");
  if (morton_) {
    // entries: storage slots in bucket order (the lookup table into the Z-ordered points)
    radixSort(keys_.data(), keys_sorted_.data(), iota_.data(), entries_.data(), bucket_bits);
  } else {
    radixSort(keys_.data(), keys_sorted_.data(), iota_.data(), perm_.data(), bucket_bits);
    // float queries read the packed copy only: the Vec3 copy is made on request (sortedPoints)
    gatherKernel<T>
        <<<blocksFor(n), kThreads, 0, st>>>(d_points, perm_.data(), ni, packed ? nullptr : sorted_.data(), packed);
    INC_CUDA_LAUNCH("gatherKernel");
  }
  mark("build:sort+gather");

  // 3. Cell table: start[b] = number of points in buckets < b (exclusive scan of the histogram; its last
  // entry, zeroed by the memset, makes start[buckets] = n).
  std::size_t bytes = temp_.size();
  INC_CUDA(cub::DeviceScan::ExclusiveScan(temp_.data(), bytes, cell_count_.data(), bucket_start_.data(),
                                          ::cuda::std::plus<std::int32_t>{}, std::int32_t(0), table, st));
  INC_CUDA(cudaStreamWaitEvent(st, join, 0));  // the read-back branch rejoins (a capture must end joined)
  mark("build:cell table scan");
}

template <typename T>
DeviceNeighborLists GridNeighborSearch<T>::querySelf(T radius) const {
  DeviceNeighborLists out;
  querySelf(radius, out);
  return out;
}

template <typename T>
void GridNeighborSearch<T>::querySelf(T radius, DeviceNeighborLists& out) const {
  ensureParams();  // n_ is known (and the points checked) from here on
  run(nullptr, n_, radius, nullptr, 1, true, out);
}

template <typename T>
void GridNeighborSearch<T>::querySelf(const T* d_radii, std::size_t radii_count, DeviceNeighborLists& out) const {
  if (!d_radii) throw InputError("", "radii", "null device pointer");
  ensureParams();
  run(nullptr, n_, T(0), d_radii, radii_count, true, out);
}

template <typename T>
DeviceNeighborLists GridNeighborSearch<T>::query(const Vec3<T>* d_queries, std::size_t nq, T radius) const {
  DeviceNeighborLists out;
  query(d_queries, nq, radius, out);
  return out;
}

template <typename T>
void GridNeighborSearch<T>::query(const Vec3<T>* d_queries, std::size_t nq, T radius, DeviceNeighborLists& out) const {
  run(d_queries, nq, radius, nullptr, 1, false, out);
}

template <typename T>
void GridNeighborSearch<T>::query(const Vec3<T>* d_queries, std::size_t nq, const T* d_radii, std::size_t radii_count,
                                  DeviceNeighborLists& out) const {
  if (!d_radii) throw InputError("", "radii", "null device pointer");
  run(d_queries, nq, T(0), d_radii, radii_count, false, out);
}

template <typename T>
void GridNeighborSearch<T>::querySelfStorage(T radius, DeviceNeighborLists& out) const {
  if (!neighborRadiusValid(radius))
    throw InputError("", "radius", "must be finite and >= 0, got " + std::to_string(double(radius)));
  ensureParams();
  const std::size_t nq = n_;
  out.offsets.resize(nq + 1);
  if (nq == 0) {
    out.offsets.fillZero();
    out.indices.resize(0);
    return;
  }
  mark("query:start");
  QuerySpec<T> s = querySpec(params_, packed_.data(), sorted_.data(), bucket_start_.data(),
                             morton_ ? entries_.data() : nullptr, perm_.data(), n_);
  s.radius = radius;
  s.nq = int(nq);
  const unsigned tiles = unsigned((nq + kFillThreads - 1) / kFillThreads);
  tile_status_.resize(std::size_t(tiles) + 1);  // + the tile counter
  // Optimistic size: the buffer's capacity (a previous call's lists), at least 32 entries per query. When the
  // lists turn out longer, the offsets are still complete: grow to the exact total and run once more.
  std::size_t cap = std::max(out.indices.capacity(), nq * 32);
  auto grow = [&](std::size_t total) {
    try {
      out.indices.resize(total);
    } catch (const std::runtime_error&) {  // cudaMalloc failed: never hand out truncated lists
      cudaGetLastError();
      throw InputError("", "radius",
                       "the neighbour lists (" + std::to_string(total) +
                           " entries) do not fit in device memory; use a smaller radius");
    }
  };
  grow(cap);
  cap = out.indices.capacity();
  for (int attempt = 0;; ++attempt) {
    INC_CUDA(cudaMemsetAsync(tile_status_.data(), 0, tile_status_.bytes()));
    storageSelfKernel<T, kStorageRowCap, kStorageMinBlocks>
        <<<tiles, kFillThreads>>>(s, out.offsets.data(), out.indices.data(), cap, tile_status_.data());
    INC_CUDA_LAUNCH("storageSelfKernel");
    // Host sync 1 of 1 (2 when the lists outgrow the buffer): the total, to size the list exactly and to know
    // whether every row was written.
    std::int64_t total = 0;
    INC_CUDA(cudaMemcpy(&total, out.offsets.data() + nq, sizeof(total), cudaMemcpyDeviceToHost));
    mark(attempt == 0 ? "query:storage traverse+write+sync" : "query:storage rerun");
    if (std::uint64_t(total) > std::uint64_t(std::numeric_limits<std::int64_t>::max() / 4))
      throw InputError("", "radius",
                       "the neighbour lists hold " + std::to_string(total) + " entries; use a smaller radius");
    if (std::size_t(total) <= cap) {
      out.indices.resize(std::size_t(total));
      return;
    }
    grow(std::size_t(total));
    cap = out.indices.capacity();
  }
}

template <typename T>
void GridNeighborSearch<T>::run(const Vec3<T>* d_queries, std::size_t nq, T radius, const T* d_radii,
                                std::size_t radii_count, bool self, DeviceNeighborLists& out) const {
  ensureParams();  // (a no-op after querySelf's own call)
  if (radii_count != 1 && radii_count != nq)
    throw InputError(
        "", "radii",
        "expected 1 radius or one per query (" + std::to_string(nq) + "), got " + std::to_string(radii_count));
  if (nq > kMaxPoints) throw InputError("", "queries", "too many queries (" + std::to_string(nq) + " > 2^30)");
  if (!self && nq > 0 && !d_queries)
    throw InputError("", "queries", "null device pointer for " + std::to_string(nq) + " queries");
  if (!d_radii && !neighborRadiusValid(radius))
    throw InputError("", "radius", "must be finite and >= 0, got " + std::to_string(double(radius)));
  out.offsets.resize(nq + 1);
  if (nq == 0) {
    out.offsets.fillZero();
    out.indices.resize(0);
    return;
  }
  const int nqi = int(nq);
  mark("query:start");
  status_.resize(3);
  INC_CUDA(cudaMemsetAsync(status_.data(), 0xff, status_.bytes()));  // "none" = all ones
  const Vec3<T>* check_queries = self ? nullptr : d_queries;         // self-query points were checked by build
  if (check_queries || d_radii) {
    const std::size_t m = std::max(check_queries ? nq : std::size_t(0), d_radii ? radii_count : std::size_t(0));
    validateKernel<T><<<blocksFor(m), kThreads>>>(check_queries, (long long)nq, d_radii, (long long)radii_count,
                                                  reinterpret_cast<unsigned long long*>(status_.data()));
    INC_CUDA_LAUNCH("validateKernel");
  }

  QuerySpec<T> s = querySpec(params_, packed_.data(), sorted_.data(), bucket_start_.data(),
                             morton_ ? entries_.data() : nullptr, perm_.data(), n_);
  s.queries = self ? nullptr : d_queries;
  s.radii = d_radii;
  s.radii_stride = radii_count == nq ? 1 : 0;  // one device radius for all: every query reads radii[0]
  s.radius = radius;
  s.nq = nqi;

  // Count pass, then offsets = exclusive scan of the counts (int64: totals beyond 2^31 stay exact).
  counts_.resize(nq + 1);
  INC_CUDA(cudaMemsetAsync(counts_.data() + nq, 0, sizeof(std::int32_t)));
  // Fused mode (the default while the staging area stays within the staging limit): one traversal counts
  // and stages the sorted rows; the second pass only copies them to their CSR place.
  const bool fused = nq * std::size_t(kRowCap) * sizeof(std::int32_t) <= staged_limit_bytes_;
  const unsigned fill_blocks = unsigned((nq + kFillThreads - 1) / kFillThreads);
  if (fused) {
    staged_.resize(std::size_t(fill_blocks) * kFillThreads * kRowCap);
    countStageKernel<T><<<fill_blocks, kFillThreads>>>(s, counts_.data(), staged_.data());
    INC_CUDA_LAUNCH("countStageKernel");
  } else {
    countKernel<T><<<blocksFor(nq), kThreads>>>(s, counts_.data());
    INC_CUDA_LAUNCH("countKernel");
  }
  mark(fused ? "query:validate+count+stage" : "query:validate+count");
  std::size_t bytes = 0;
  INC_CUDA(cub::DeviceScan::ExclusiveScan(nullptr, bytes, counts_.data(), out.offsets.data(),
                                          ::cuda::std::plus<std::int64_t>{}, std::int64_t(0), nq + 1));
  void* tmp = scratch(bytes);
  INC_CUDA(cub::DeviceScan::ExclusiveScan(tmp, bytes, counts_.data(), out.offsets.data(),
                                          ::cuda::std::plus<std::int64_t>{}, std::int64_t(0), nq + 1));
  totalKernel<<<1, 1>>>(out.offsets.data(), nq, reinterpret_cast<unsigned long long*>(status_.data()));
  INC_CUDA_LAUNCH("totalKernel");
  mark("query:offsets scan");

  // Host sync 1 of 1 in a query: the total sizes the index array (exact, so nothing is truncated), and an
  // invalid query or radius found by validateKernel is reported before any list is handed out.
  std::uint64_t st[3];
  INC_CUDA(cudaMemcpy(st, status_.data(), sizeof(st), cudaMemcpyDeviceToHost));
  if (st[0] != kNone) {
    Vec3<T> bad;
    INC_CUDA(cudaMemcpy(&bad, d_queries + st[0], sizeof(bad), cudaMemcpyDeviceToHost));
    throw InputError("", "queries[" + std::to_string(st[0]) + "]", "position " + describe(bad) + " is not finite");
  }
  if (st[1] != kNone) {
    T bad = T(0);
    INC_CUDA(cudaMemcpy(&bad, d_radii + st[1], sizeof(bad), cudaMemcpyDeviceToHost));
    throw InputError("", radii_count == 1 ? std::string("radius") : "radii[" + std::to_string(st[1]) + "]",
                     "must be finite and >= 0, got " + std::to_string(double(bad)));
  }
  const std::uint64_t total = st[2];
  if (total > std::uint64_t(std::numeric_limits<std::int64_t>::max() / 4))
    throw InputError("", "radius",
                     "the neighbour lists hold " + std::to_string(total) + " entries; use a smaller radius");
  try {
    out.indices.resize(std::size_t(total));
  } catch (const std::runtime_error&) {  // cudaMalloc failed: never hand out truncated lists
    cudaGetLastError();  // clear the allocation error so that later launch checks do not report it again
    throw InputError("", "radius",
                     "the neighbour lists (" + std::to_string(total) +
                         " entries) do not fit in device memory; use a smaller radius");
  }
  mark("query:sync+alloc");
  if (total == 0) return;
  fillKernel<T>
      <<<fill_blocks, kFillThreads>>>(s, out.offsets.data(), fused ? staged_.data() : nullptr, out.indices.data());
  INC_CUDA_LAUNCH("fillKernel");
  mark(fused ? "query:copy staged rows" : "query:fill+sort");
}

template class GridNeighborSearch<float>;
template class GridNeighborSearch<double>;

}  // namespace inc::cuda
