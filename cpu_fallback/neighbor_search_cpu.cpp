// CPU uniform-grid neighbour search: counting sort by bucket, a vector scan of whole cell rows (AVX2 or SSE2),
// per-block lists.
#include "cpu_fallback/neighbor_search_cpu.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <limits>
#include <new>
#include <sstream>
#include <string>

#if defined(__x86_64__) || defined(__SSE2__)
#include <immintrin.h>
#endif

#include "base/parallel.h"
#include "model/input_error.h"

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
    for (std::size_t i = 0; i < n; ++i)
      tmp[std::size_t(count[(keys[std::size_t(idx[i])] >> shift) & 1023u]++)] = idx[i];
    idx.swap(tmp);
  }
  return idx;
}

// No FMA contraction in the query code between these markers: d^2 must round exactly like distance2Exact
// ((dx^2 + dy^2) + dz^2, each operation rounded on its own). Everything the per-block loop inlines sits
// inside, so that the optimisation options agree where GCC inlines.
#if defined(__clang__)
#define INC_NO_CONTRACT_BEGIN _Pragma("STDC FP_CONTRACT OFF")
#define INC_NO_CONTRACT_END _Pragma("STDC FP_CONTRACT ON")
#elif defined(__GNUC__)
#define INC_NO_CONTRACT_BEGIN _Pragma("GCC push_options") _Pragma("GCC optimize(\"fp-contract=off\")")
#define INC_NO_CONTRACT_END _Pragma("GCC pop_options")
#else
#define INC_NO_CONTRACT_BEGIN
#define INC_NO_CONTRACT_END
#endif

#if (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__)
#define INC_NEIGHBOR_AVX2 1
#define INC_TARGET_AVX2 __attribute__((target("avx2,popcnt")))
#else
#define INC_NEIGHBOR_AVX2 0
#endif
#if defined(__GNUC__) || defined(__clang__)
#define INC_FORCE_INLINE inline __attribute__((always_inline))
#define INC_NOINLINE __attribute__((noinline))
#else
#define INC_FORCE_INLINE inline
#define INC_NOINLINE
#endif

// Lanes read past the end of a run (masked off, never listed): the slot arrays carry this many extra entries.
constexpr std::size_t kRunPad = 8;
// Entries a scan may write past its last neighbour (the lanes of a vector store that are not kept).
constexpr std::size_t kScanSlack = 8;

std::atomic<bool> g_scan_portable_only{false};

bool cpuHasAvx2() {
#if INC_NEIGHBOR_AVX2
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
  return has;
#else
  return false;
#endif
}

INC_NO_CONTRACT_BEGIN

// Lists are short (tens of entries): insertion sort beats std::sort's set-up there.
INC_FORCE_INLINE void sortList(std::int32_t* a, std::size_t k) {
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

// One query's candidates on a dense grid: rows_z planes of rows_y rows of cells, each row the contiguous run
// of bucket slots [start[b], start[b + width]) of its first bucket b, which advances by dx per row and by dxy
// per plane from b0.
template <typename T>
struct QueryRows {
  const T *xs, *ys, *zs;      // coordinates in bucket-slot order
  const std::int32_t* ids;    // the id each slot is listed as (original index or storage slot)
  const std::int32_t* start;  // bucket start table
  std::uint32_t b0, dx, dxy, width, rows_y, rows_z;
  T qx, qy, qz, r2;
  std::int32_t skip;  // the query's own id (self-queries), else -1
};

// The scans. query() writes the ids of every slot of the rows with d^2 <= r2 and an id other than skip, in
// slot order, and sorts them when asked; it returns the end. d = query - point, d^2 = (dx^2 + dy^2) + dz^2,
// each operation rounded on its own (distance2Exact). A scan reads up to kRunPad slots past the end of a run
// (masked off) and writes up to kScanSlack entries past the end of the row (lanes that are not kept), and a
// row of at most kSortWidth is sorted in a block of kSortWidth entries: the destination needs room for
// max(candidates, kSortWidth) + kScanSlack.
constexpr std::size_t kSortWidth = 32;

// Portable: four floats or two doubles per step with SSE2 (any x86-64), one at a time elsewhere. The kept
// ids are stored branch-free: every lane writes at dst, and dst advances by that lane's bit.
struct PortableScan {
  template <typename T>
  static INC_FORCE_INLINE std::int32_t* query(const QueryRows<T>& rows, bool sort, std::int32_t* dst) {
    const QueryRows<T> w = rows;  // a local copy: the stores through dst cannot change it, so it stays in registers
    std::int32_t* const first = dst;
    for (std::uint32_t z = 0, b = w.b0; z < w.rows_z; ++z, b += w.dxy)
      for (std::uint32_t y = 0, by = b; y < w.rows_y; ++y, by += w.dx)
        dst = run(w, w.start[by], w.start[by + w.width], dst);
    if (sort) sortList(first, std::size_t(dst - first));
    return dst;
  }
  template <typename T>
  static INC_FORCE_INLINE std::int32_t* run(const QueryRows<T>& w, std::int32_t e, std::int32_t e1, std::int32_t* dst) {
    for (; e < e1; ++e) {
      const T dx = w.qx - w.xs[e], dy = w.qy - w.ys[e], dz = w.qz - w.zs[e];
      const T xx = dx * dx, yy = dy * dy, zz = dz * dz;
      const T d2 = (xx + yy) + zz;
      const std::int32_t o = w.ids[e];
      *dst = o;
      dst += (d2 <= w.r2) & (o != w.skip);
    }
    return dst;
  }
#if defined(__SSE2__)
  static INC_FORCE_INLINE std::int32_t* run(const QueryRows<float>& w, std::int32_t e, std::int32_t e1,
                                            std::int32_t* dst) {
    const __m128 vx = _mm_set1_ps(w.qx), vy = _mm_set1_ps(w.qy), vz = _mm_set1_ps(w.qz), vr2 = _mm_set1_ps(w.r2);
    const __m128i vskip = _mm_set1_epi32(w.skip), vend = _mm_set1_epi32(e1);
    __m128i lane = _mm_add_epi32(_mm_set1_epi32(e), _mm_set_epi32(3, 2, 1, 0));
    for (; e < e1; e += 4) {
      const __m128 dx = _mm_sub_ps(vx, _mm_loadu_ps(w.xs + e));
      const __m128 dy = _mm_sub_ps(vy, _mm_loadu_ps(w.ys + e));
      const __m128 dz = _mm_sub_ps(vz, _mm_loadu_ps(w.zs + e));
      const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
      const __m128i o = _mm_loadu_si128(reinterpret_cast<const __m128i*>(w.ids + e));
      // kept: d2 <= r2 (false for NaN), not the skipped id, lane inside the run
      const __m128i keep = _mm_andnot_si128(_mm_cmpeq_epi32(o, vskip), _mm_cmplt_epi32(lane, vend));
      const unsigned bits = unsigned(_mm_movemask_ps(_mm_and_ps(_mm_cmple_ps(d2, vr2), _mm_castsi128_ps(keep))));
      lane = _mm_add_epi32(lane, _mm_set1_epi32(4));
      dst[0] = w.ids[e];
      dst += bits & 1u;
      dst[0] = w.ids[e + 1];
      dst += (bits >> 1) & 1u;
      dst[0] = w.ids[e + 2];
      dst += (bits >> 2) & 1u;
      dst[0] = w.ids[e + 3];
      dst += bits >> 3;
    }
    return dst;
  }
  static INC_FORCE_INLINE std::int32_t* run(const QueryRows<double>& w, std::int32_t e, std::int32_t e1,
                                            std::int32_t* dst) {
    const __m128d vx = _mm_set1_pd(w.qx), vy = _mm_set1_pd(w.qy), vz = _mm_set1_pd(w.qz), vr2 = _mm_set1_pd(w.r2);
    for (; e < e1; e += 2) {
      const __m128d dx = _mm_sub_pd(vx, _mm_loadu_pd(w.xs + e));
      const __m128d dy = _mm_sub_pd(vy, _mm_loadu_pd(w.ys + e));
      const __m128d dz = _mm_sub_pd(vz, _mm_loadu_pd(w.zs + e));
      const __m128d d2 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), _mm_mul_pd(dz, dz));
      const unsigned bits = unsigned(_mm_movemask_pd(_mm_cmple_pd(d2, vr2)));
      const std::int32_t o0 = w.ids[e], o1 = w.ids[e + 1];
      dst[0] = o0;
      dst += (bits & 1u) & unsigned(o0 != w.skip);
      dst[0] = o1;
      dst += (bits >> 1) & unsigned(o1 != w.skip) & unsigned(e + 1 < e1);
    }
    return dst;
  }
#endif
};

#if INC_NEIGHBOR_AVX2
// For each 8-bit mask, the lanes of its set bits in ascending order, one per nibble (for a permute that packs
// the kept lanes to the front).
struct CompressTable {
  std::uint32_t lanes[256];
  constexpr CompressTable() : lanes() {
    for (unsigned m = 0; m < 256; ++m) {
      unsigned k = 0;
      for (unsigned i = 0; i < 8; ++i)
        if ((m >> i) & 1u) lanes[m] |= i << (4 * k++);
    }
  }
};
constexpr CompressTable kCompress{};

// Bitonic sorting network on 32 values in four 8-lane registers (value i in lane i % 8 of register i / 8):
// for block size k = 2, 4, .., 32 and distance j = k / 2, .., 1, value i and i ^ j swap into order, ascending
// where i & k == 0. Lanes that take the larger value of their pair at step (k, j) in register reg:
constexpr int bitonicMaxLanes(int k, int j, int reg) {
  int mask = 0;
  for (int lane = 0; lane < 8; ++lane) {
    const int i = 8 * reg + lane;
    if (((i & k) == 0) != ((i & j) == 0)) mask |= 1 << lane;
  }
  return mask;
}

// AVX2: eight floats or four doubles per step; the kept ids are packed to the front by one permute (the lane
// order from kCompress) and stored as a vector, and dst advances by the number of kept lanes. Rows of up to
// 32 ids are sorted by the bitonic network, branch-free. query() is the one AVX2 function the query loop
// calls (once per query, not inlined: GCC inlines AVX2 code only into AVX2 functions).
struct Avx2Scan {
  template <typename T>
  INC_TARGET_AVX2 static INC_NOINLINE std::int32_t* query(const QueryRows<T>& rows, bool sort, std::int32_t* dst) {
    const QueryRows<T> w = rows;  // a local copy: the stores through dst cannot change it, so it stays in registers
    std::int32_t* const first = dst;
    for (std::uint32_t z = 0, b = w.b0; z < w.rows_z; ++z, b += w.dxy)
      for (std::uint32_t y = 0, by = b; y < w.rows_y; ++y, by += w.dx)
        dst = run(w, w.start[by], w.start[by + w.width], dst);
    const std::size_t k = std::size_t(dst - first);
    if (sort && k <= kSortWidth)
      sort32(first, k);
    else if (sort)
      sortList(first, k);
    return dst;
  }

  INC_TARGET_AVX2 static INC_FORCE_INLINE __m256i packOrder(unsigned bits) {
    const __m256i shifts = _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28);
    return _mm256_and_si256(_mm256_srlv_epi32(_mm256_set1_epi32(std::int32_t(kCompress.lanes[bits])), shifts),
                            _mm256_set1_epi32(7));
  }
  INC_TARGET_AVX2 static INC_FORCE_INLINE std::int32_t* run(const QueryRows<float>& w, std::int32_t e, std::int32_t e1,
                                                            std::int32_t* dst) {
    const __m256 vx = _mm256_set1_ps(w.qx), vy = _mm256_set1_ps(w.qy), vz = _mm256_set1_ps(w.qz);
    const __m256 vr2 = _mm256_set1_ps(w.r2);
    const __m256i vskip = _mm256_set1_epi32(w.skip), vend = _mm256_set1_epi32(e1);
    __m256i lane = _mm256_add_epi32(_mm256_set1_epi32(e), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    for (; e < e1; e += 8) {
      const __m256 dx = _mm256_sub_ps(vx, _mm256_loadu_ps(w.xs + e));
      const __m256 dy = _mm256_sub_ps(vy, _mm256_loadu_ps(w.ys + e));
      const __m256 dz = _mm256_sub_ps(vz, _mm256_loadu_ps(w.zs + e));
      const __m256 d2 =
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
      const __m256i o = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(w.ids + e));
      const __m256i keep = _mm256_andnot_si256(_mm256_cmpeq_epi32(o, vskip), _mm256_cmpgt_epi32(vend, lane));
      const unsigned bits =
          unsigned(_mm256_movemask_ps(_mm256_and_ps(_mm256_cmp_ps(d2, vr2, _CMP_LE_OQ), _mm256_castsi256_ps(keep))));
      lane = _mm256_add_epi32(lane, _mm256_set1_epi32(8));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst), _mm256_permutevar8x32_epi32(o, packOrder(bits)));
      dst += __builtin_popcount(bits);
    }
    return dst;
  }
  INC_TARGET_AVX2 static INC_FORCE_INLINE std::int32_t* run(const QueryRows<double>& w, std::int32_t e, std::int32_t e1,
                                                            std::int32_t* dst) {
    const __m256d vx = _mm256_set1_pd(w.qx), vy = _mm256_set1_pd(w.qy), vz = _mm256_set1_pd(w.qz);
    const __m256d vr2 = _mm256_set1_pd(w.r2);
    const __m128i vskip = _mm_set1_epi32(w.skip), vend = _mm_set1_epi32(e1);
    __m128i lane = _mm_add_epi32(_mm_set1_epi32(e), _mm_setr_epi32(0, 1, 2, 3));
    for (; e < e1; e += 4) {
      const __m256d dx = _mm256_sub_pd(vx, _mm256_loadu_pd(w.xs + e));
      const __m256d dy = _mm256_sub_pd(vy, _mm256_loadu_pd(w.ys + e));
      const __m256d dz = _mm256_sub_pd(vz, _mm256_loadu_pd(w.zs + e));
      const __m256d d2 =
          _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
      const __m128i o = _mm_loadu_si128(reinterpret_cast<const __m128i*>(w.ids + e));
      const __m128i keep = _mm_andnot_si128(_mm_cmpeq_epi32(o, vskip), _mm_cmpgt_epi32(vend, lane));
      const unsigned bits = unsigned(_mm256_movemask_pd(
          _mm256_and_pd(_mm256_cmp_pd(d2, vr2, _CMP_LE_OQ), _mm256_castsi256_pd(_mm256_cvtepi32_epi64(keep)))));
      lane = _mm_add_epi32(lane, _mm_set1_epi32(4));
      // (4-bit masks only name lanes 0-3, so the undefined upper half of the cast is never read into the store)
      const __m256i packed = _mm256_permutevar8x32_epi32(_mm256_castsi128_si256(o), packOrder(bits));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(dst), _mm256_castsi256_si128(packed));
      dst += __builtin_popcount(bits);
    }
    return dst;
  }

  // One step (k, j) of the network on register reg: min and max against the partner lane, then a blend.
  template <int K, int J, int R>
  INC_TARGET_AVX2 static INC_FORCE_INLINE __m256i sortLanes(__m256i v) {
    __m256i partner;
    if constexpr (J == 1)
      partner = _mm256_shuffle_epi32(v, 0xB1);
    else if constexpr (J == 2)
      partner = _mm256_shuffle_epi32(v, 0x4E);
    else
      partner = _mm256_permute4x64_epi64(v, 0x4E);
    return _mm256_blend_epi32(_mm256_min_epi32(v, partner), _mm256_max_epi32(v, partner), bitonicMaxLanes(K, J, R));
  }
  template <int K, int J>
  INC_TARGET_AVX2 static INC_FORCE_INLINE void sortStep(__m256i (&x)[4]) {
    if constexpr (J >= 8) {  // partners in registers r and r + J / 8
      constexpr int d = J / 8;
      for (int r = 0; r < 4; ++r) {
        if (r & d) continue;
        const __m256i lo = _mm256_min_epi32(x[r], x[r + d]), hi = _mm256_max_epi32(x[r], x[r + d]);
        const bool ascending = ((8 * r) & K) == 0;
        x[r] = ascending ? lo : hi;
        x[r + d] = ascending ? hi : lo;
      }
    } else {
      x[0] = sortLanes<K, J, 0>(x[0]);
      x[1] = sortLanes<K, J, 1>(x[1]);
      x[2] = sortLanes<K, J, 2>(x[2]);
      x[3] = sortLanes<K, J, 3>(x[3]);
    }
  }
  // Sorts a[0..k), k <= 32; lanes past k are filled with INT32_MAX, sort to the end and are stored after the
  // row (into the room the caller reserved).
  INC_TARGET_AVX2 static INC_FORCE_INLINE void sort32(std::int32_t* a, std::size_t k) {
    __m256i x[4];
    const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256i pad = _mm256_set1_epi32(std::numeric_limits<std::int32_t>::max());
    for (int c = 0; c < 4; ++c) {
      const __m256i inside = _mm256_cmpgt_epi32(_mm256_set1_epi32(std::int32_t(k) - 8 * c), lanes);
      x[c] = _mm256_blendv_epi8(pad, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(a + 8 * c)), inside);
    }
    sortStep<2, 1>(x);
    sortStep<4, 2>(x);
    sortStep<4, 1>(x);
    sortStep<8, 4>(x);
    sortStep<8, 2>(x);
    sortStep<8, 1>(x);
    sortStep<16, 8>(x);
    sortStep<16, 4>(x);
    sortStep<16, 2>(x);
    sortStep<16, 1>(x);
    sortStep<32, 16>(x);
    sortStep<32, 8>(x);
    sortStep<32, 4>(x);
    sortStep<32, 2>(x);
    sortStep<32, 1>(x);
    for (int c = 0; c < 4; ++c) _mm256_storeu_si256(reinterpret_cast<__m256i*>(a + 8 * c), x[c]);
  }
};
#endif

// What the per-block query loop reads.
template <typename T>
struct QueryJob {
  NeighborGridView<T> g;     // the generic traversal's view (storage order)
  const T *xs, *ys, *zs;     // the dense fast path's coordinates in bucket-slot order
  const std::int32_t* ids;   // ... and the id each slot is listed as (original index or storage slot)
  const std::int32_t* perm;  // storage slot -> original index; null for storage-order lists
  const Vec3<T>* queries;    // null for self-queries (the queries are the stored points)
  const T* radii;
  bool per_query;
  bool sort_rows;        // false where the fast path visits the ids in ascending order
  std::int64_t* counts;  // counts[q]: row q's length
};

// Appends perm[j] (original index), or j itself when perm is null (storage-order lists).
struct AppendIndex {
  detail::IndexBuffer* out;
  const std::int32_t* perm;
  void operator()(std::int32_t j) { out->push(perm ? perm[j] : j); }
};

// The shared traversal (hashed grids, huge radii): appends the neighbours of x to buf, unsorted.
template <typename T>
INC_NOINLINE void genericQuery(const QueryJob<T>& job, const Vec3<T>& x, T r, std::int32_t skip,
                               detail::IndexBuffer& buf) {
  AppendIndex visit{&buf, job.perm};
  forEachGridNeighbor(job.g, x, r, skip, visit);
}

// Dense-grid fast path of forEachGridNeighbor: the same cell range, so no neighbour can be missed, and the same
// d^2 decision, so the same set, sorted unless job.sort_rows says it is already. Each (y, z) row of the range
// is one contiguous run of bucket slots, scanned over separate coordinate arrays. Rows are not trimmed to the
// ball (neighborRowXRange): with a vector scan, testing a row's extra candidates costs less than computing its
// trimmed range. Writes the neighbours at buf.data + buf.size and returns their number, or -1 where the
// generic traversal must be used (hashed grid, or a range with more cells than points).
template <typename Scan, typename T>
INC_FORCE_INLINE std::int64_t denseQuery(const QueryJob<T>& job, const Vec3<T>& x, T r, std::int32_t skip,
                                         detail::IndexBuffer& buf) {
  const NeighborGridParams<T>& p = job.g.p;
  if (!p.dense) return -1;
  const std::int32_t n = job.g.n;
  if (n <= 0) return 0;
  const T reach = neighborSearchReach(r);
  std::int32_t lo[3], hi[3];
  std::uint64_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    lo[a] = neighborCellCoord(x[a] - reach, p.origin[a], neighborInvCell(p, a));
    const std::int32_t h = neighborCellCoord(x[a] + reach, p.origin[a], neighborInvCell(p, a));
    hi[a] = h < p.dims[a] - 1 ? h : p.dims[a] - 1;
    if (lo[a] > hi[a]) return 0;
    cells *= std::uint64_t(hi[a] - lo[a] + 1);
  }
  if (cells > std::uint64_t(n)) return -1;
  QueryRows<T> w;
  w.xs = job.xs;
  w.ys = job.ys;
  w.zs = job.zs;
  w.ids = job.ids;
  w.start = job.g.bucket_start;
  w.dx = std::uint32_t(p.dims[0]);
  w.dxy = w.dx * std::uint32_t(p.dims[1]);
  w.b0 = std::uint32_t(lo[0]) + w.dx * std::uint32_t(lo[1]) + w.dxy * std::uint32_t(lo[2]);
  w.width = std::uint32_t(hi[0] - lo[0]) + 1u;
  w.rows_y = std::uint32_t(hi[1] - lo[1]) + 1u;
  w.rows_z = std::uint32_t(hi[2] - lo[2]) + 1u;
  w.qx = x.x;
  w.qy = x.y;
  w.qz = x.z;
  w.r2 = r * r;
  w.skip = skip;
  // Every candidate lies between the first row's first slot and the last row's last one: room for all of them.
  const std::uint32_t b_end = w.b0 + (w.rows_z - 1u) * w.dxy + (w.rows_y - 1u) * w.dx + w.width;
  const std::size_t bound = std::size_t(w.start[b_end] - w.start[w.b0]);
  std::int32_t* const first = buf.room(std::max(bound, kSortWidth) + kScanSlack);
  return Scan::query(w, job.sort_rows, first) - first;
}

// Queries [i0, i1) (storage order for self-queries, for locality): each sorted row is appended to buf and its
// length written to counts.
template <typename Scan, typename T>
INC_FORCE_INLINE void queryBlock(const QueryJob<T>& job, std::size_t i0, std::size_t i1, detail::IndexBuffer& buf) {
  const bool self = job.queries == nullptr;
  buf.room((i1 - i0) * 32);  // a first guess (never initialised, so pages that stay unused cost nothing)
  for (std::size_t i = i0; i < i1; ++i) {
    const std::size_t q = self && job.perm ? std::size_t(job.perm[i]) : i;
    const Vec3<T> x = self ? job.g.points[i] : job.queries[i];
    const T r = job.per_query ? job.radii[q] : job.radii[0];
    // the query itself, as the fast path lists it (its id) and as the generic one sees it (its storage slot)
    const std::int32_t skip_id = self ? std::int32_t(q) : -1, skip_slot = self ? std::int32_t(i) : -1;
    const std::size_t first = buf.size;
    std::int64_t k = denseQuery<Scan>(job, x, r, skip_id, buf);  // sorted
    if (k < 0) {
      genericQuery(job, x, r, skip_slot, buf);
      k = std::int64_t(buf.size - first);
      sortList(buf.data.get() + first, std::size_t(k));
    }
    buf.size = first + std::size_t(k);
    job.counts[q] = k;
  }
}

template <typename T>
void queryBlockPortable(const QueryJob<T>& job, std::size_t i0, std::size_t i1, detail::IndexBuffer& buf) {
  queryBlock<PortableScan>(job, i0, i1, buf);
}

#if INC_NEIGHBOR_AVX2
// The same loop with the AVX2 scan (only called when the CPU has it).
template <typename T>
void queryBlockAvx2(const QueryJob<T>& job, std::size_t i0, std::size_t i1, detail::IndexBuffer& buf) {
  queryBlock<Avx2Scan>(job, i0, i1, buf);
}
#endif

INC_NO_CONTRACT_END

}  // namespace

template <typename T>
void GridNeighborSearch<T>::build(const std::vector<Vec3<T>>& points, T cell_size, bool morton_order) {
  checkCellSize(cell_size);
  const std::size_t n = points.size();
  if (n > kMaxPoints)
    throw InputError("", "points", "too many points for the grid search (" + std::to_string(n) + " > 2^30)");
  // One parallel pass: each chunk's first non-finite point and bounding box (exact min / max: the chunking
  // changes nothing). The lowest bad index is the one reported.
  const std::int64_t chunks = std::max<std::int64_t>(1, std::min<std::int64_t>(std::int64_t(n), threadCount()));
  std::vector<std::size_t> first_bad(std::size_t(chunks), n);
  std::vector<Vec3<T>> chunk_lo(static_cast<std::size_t>(chunks)), chunk_hi(static_cast<std::size_t>(chunks));
  parallelFor(chunks, [&](std::int64_t c) {
    const std::size_t i0 = std::size_t(c) * n / std::size_t(chunks), i1 = std::size_t(c + 1) * n / std::size_t(chunks);
    if (i0 == i1) return;
    T lx = points[i0].x, ly = points[i0].y, lz = points[i0].z, hx = lx, hy = ly, hz = lz;
    for (std::size_t i = i0; i < i1; ++i) {
      const T x = points[i].x, y = points[i].y, z = points[i].z;
      // x - x is 0 for finite x and NaN for NaN and +-inf (neighborPointFinite), and NaN survives the sum
      if (!(((x - x) + (y - y)) + (z - z) == T(0))) {
        first_bad[std::size_t(c)] = i;
        break;
      }
      lx = std::min(lx, x);
      ly = std::min(ly, y);
      lz = std::min(lz, z);
      hx = std::max(hx, x);
      hy = std::max(hy, y);
      hz = std::max(hz, z);
    }
    chunk_lo[std::size_t(c)] = Vec3<T>(lx, ly, lz);
    chunk_hi[std::size_t(c)] = Vec3<T>(hx, hy, hz);
  });
  for (std::size_t i : first_bad)
    if (i < n)
      throw InputError("", "points[" + std::to_string(i) + "]", "position " + describe(points[i]) + " is not finite");
  cell_size_ = cell_size;
  morton_ = morton_order;
  Vec3<T> lo = chunk_lo[0], hi = chunk_hi[0];
  for (std::size_t c = 1; c < std::size_t(chunks); ++c)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], chunk_lo[c][a]);
      hi[a] = std::max(hi[a], chunk_hi[c][a]);
    }
  const std::uint32_t buckets = neighborBucketCount(n);
  params_ = makeNeighborGridParams(lo, hi, cell_size, buckets, std::int64_t(n), n > 0);
  const NeighborGridParams<T> p = params_;
  // Start table: one entry per occupied cell of a dense grid (as on the GPU), else one per hash bucket.
  const std::uint32_t table =
      p.dense ? std::uint32_t(p.dims[0]) * std::uint32_t(p.dims[1]) * std::uint32_t(p.dims[2]) : buckets;
  auto cellOf = [&p](const Vec3<T>& x, std::int32_t c[3]) {
    for (int a = 0; a < 3; ++a) c[a] = neighborCellCoord(x[a], p.origin[a], neighborInvCell(p, a));
  };

  keys_.resize(n);
  std::vector<std::uint32_t>& keys = keys_;
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
  if (morton_order)
    parallelFor(std::int64_t(n),
                [&](std::int64_t s) { sorted_[std::size_t(s)] = points[std::size_t(perm_[std::size_t(s)])]; });
  const std::vector<Vec3<T>>& keyed = morton_order ? sorted_ : points;
  parallelFor(std::int64_t(n), [&](std::int64_t i) {
    std::int32_t c[3];
    cellOf(keyed[std::size_t(i)], c);
    keys[std::size_t(i)] = neighborBucket(p, c[0], c[1], c[2]);
  });
  countingSortByKey(keys, table, morton_order ? entries_ : perm_, bucket_start_);
  if (!morton_order) entries_.clear();
  // kRunPad readable entries past the end for the vectorised scan (never listed: masked off)
  inv_perm_.resize(n);
  slot_x_.resize(n + kRunPad);
  slot_y_.resize(n + kRunPad);
  slot_z_.resize(n + kRunPad);
  slot_orig_.resize(n + kRunPad);
  slot_store_.resize(n + kRunPad);
  for (std::size_t e = n; e < n + kRunPad; ++e) {
    slot_x_[e] = slot_y_[e] = slot_z_[e] = T(0);
    slot_orig_[e] = slot_store_[e] = -1;
  }
  // One gather pass: bucket slot e holds storage slot s (e itself unless Morton), which holds original point
  // perm[s]; bucket order is storage order, so the sorted points are gathered here too.
  parallelFor(std::int64_t(n), [&](std::int64_t e) {
    const std::size_t s = morton_order ? std::size_t(entries_[std::size_t(e)]) : std::size_t(e);
    const std::int32_t o = perm_[s];
    const Vec3<T> x = points[std::size_t(o)];
    if (!morton_order) sorted_[s] = x;
    inv_perm_[std::size_t(o)] = std::int32_t(s);
    slot_x_[std::size_t(e)] = x.x;
    slot_y_[std::size_t(e)] = x.y;
    slot_z_[std::size_t(e)] = x.z;
    slot_orig_[std::size_t(e)] = o;
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
  NeighborLists out;
  querySelf(radius, out);
  return out;
}

template <typename T>
NeighborLists GridNeighborSearch<T>::querySelf(const std::vector<T>& radii) const {
  NeighborLists out;
  querySelf(radii, out);
  return out;
}

template <typename T>
NeighborLists GridNeighborSearch<T>::querySelfStorage(T radius) const {
  NeighborLists out;
  querySelfStorage(radius, out);
  return out;
}

template <typename T>
NeighborLists GridNeighborSearch<T>::query(const std::vector<Vec3<T>>& queries, const std::vector<T>& radii) const {
  NeighborLists out;
  query(queries, radii, out);
  return out;
}

template <typename T>
NeighborLists GridNeighborSearch<T>::query(const std::vector<Vec3<T>>& queries, T radius) const {
  NeighborLists out;
  query(queries, radius, out);
  return out;
}

template <typename T>
void GridNeighborSearch<T>::querySelf(T radius, NeighborLists& out) const {
  run(nullptr, size(), std::vector<T>{radius}, true, false, out);
}

template <typename T>
void GridNeighborSearch<T>::querySelf(const std::vector<T>& radii, NeighborLists& out) const {
  run(nullptr, size(), radii, true, false, out);
}

template <typename T>
void GridNeighborSearch<T>::querySelfStorage(T radius, NeighborLists& out) const {
  run(nullptr, size(), std::vector<T>{radius}, true, true, out);
}

template <typename T>
void GridNeighborSearch<T>::query(const std::vector<Vec3<T>>& queries, const std::vector<T>& radii,
                                  NeighborLists& out) const {
  run(queries.data(), queries.size(), radii, false, false, out);
}

template <typename T>
void GridNeighborSearch<T>::query(const std::vector<Vec3<T>>& queries, T radius, NeighborLists& out) const {
  run(queries.data(), queries.size(), std::vector<T>{radius}, false, false, out);
}

namespace {

// Radii: one, or one per query, each finite and >= 0; queries other than the built points finite.
template <typename T>
void checkQueries(const Vec3<T>* queries, std::size_t nq, const std::vector<T>& radii, bool self) {
  if (radii.size() != 1 && radii.size() != nq)
    throw InputError(
        "", "radii",
        "expected 1 radius or one per query (" + std::to_string(nq) + "), got " + std::to_string(radii.size()));
  if (nq > kMaxPoints) throw InputError("", "queries", "too many queries (" + std::to_string(nq) + " > 2^30)");
  for (std::size_t i = 0; i < radii.size(); ++i)
    if (!neighborRadiusValid(radii[i]))
      throw InputError("", radii.size() == 1 ? std::string("radius") : "radii[" + std::to_string(i) + "]",
                       "must be finite and >= 0, got " + std::to_string(double(radii[i])));
  if (!self)
    for (std::size_t i = 0; i < nq; ++i)
      if (!neighborPointFinite(queries[i]))
        throw InputError("", "queries[" + std::to_string(i) + "]",
                         "position " + describe(queries[i]) + " is not finite");
}

// The queries split into `count` blocks (one per thread): block b is [begin(b), begin(b + 1)).
struct QueryBlocks {
  std::int64_t count;
  std::size_t nq;
  std::size_t begin(std::int64_t b) const { return std::size_t(b * std::int64_t(nq) / count); }
};

// Each block of queries appends its sorted rows to its own buffer and records their lengths. Returns false
// where a block ran out of memory (its buffer is then dropped; exceptions must not leave the OpenMP region).
template <typename T>
bool queryAllBlocks(const QueryJob<T>& job, const QueryBlocks& qb, std::vector<detail::IndexBuffer>& buffers) {
  std::vector<char> out_of_memory(std::size_t(qb.count), 0);
  const bool avx2 = neighborScanUsesAvx2();
  parallelFor(qb.count, [&](std::int64_t b) {
    detail::IndexBuffer& buf = buffers[std::size_t(b)];
    buf.size = 0;
    try {
#if INC_NEIGHBOR_AVX2
      if (avx2) {
        queryBlockAvx2(job, qb.begin(b), qb.begin(b + 1), buf);
        return;
      }
#endif
      queryBlockPortable(job, qb.begin(b), qb.begin(b + 1), buf);
    } catch (const std::bad_alloc&) {
      out_of_memory[std::size_t(b)] = 1;
      buf = detail::IndexBuffer{};
    }
  });
  (void)avx2;
  return std::find(out_of_memory.begin(), out_of_memory.end(), 1) == out_of_memory.end();
}

// Block b holds rows [i0, i1) back to back: its offsets are a running sum from its base, its buffer one copy.
void placeBlockRows(const QueryBlocks& qb, const std::vector<std::int64_t>& block_base,
                    const std::vector<detail::IndexBuffer>& buffers, NeighborLists& out) {
  std::int64_t* const offsets = out.offsets.data();
  std::int32_t* const indices = out.indices.data();
  parallelFor(qb.count, [&](std::int64_t b) {
    std::int64_t at = block_base[std::size_t(b)];
    for (std::size_t i = qb.begin(b); i < qb.begin(b + 1); ++i) offsets[i + 1] = at += offsets[i + 1];
    const detail::IndexBuffer& buf = buffers[std::size_t(b)];
    if (buf.size) std::memcpy(indices + block_base[std::size_t(b)], buf.data.get(), buf.size * sizeof(std::int32_t));
  });
}

// Original-order rows (row q = perm[i] for query i): a prefix sum over q (chunk sums, then each chunk's running
// sum from its base), then each block copies its rows to their places.
void placeScatteredRows(const QueryBlocks& qb, const std::vector<std::int32_t>& perm,
                        const std::vector<detail::IndexBuffer>& buffers, NeighborLists& out) {
  std::int64_t* const offsets = out.offsets.data();
  std::int32_t* const indices = out.indices.data();
  std::vector<std::int64_t> chunk_base(std::size_t(qb.count) + 1, 0);
  parallelFor(qb.count, [&](std::int64_t b) {
    std::int64_t sum = 0;
    for (std::size_t q = qb.begin(b); q < qb.begin(b + 1); ++q) sum += offsets[q + 1];
    chunk_base[std::size_t(b) + 1] = sum;
  });
  for (std::int64_t b = 0; b < qb.count; ++b) chunk_base[std::size_t(b) + 1] += chunk_base[std::size_t(b)];
  parallelFor(qb.count, [&](std::int64_t b) {
    std::int64_t at = chunk_base[std::size_t(b)];
    for (std::size_t q = qb.begin(b); q < qb.begin(b + 1); ++q) offsets[q + 1] = at += offsets[q + 1];
  });
  parallelFor(qb.count, [&](std::int64_t b) {
    const std::int32_t* src = buffers[std::size_t(b)].data.get();
    for (std::size_t i = qb.begin(b); i < qb.begin(b + 1); ++i) {
      const std::size_t q = std::size_t(perm[i]);
      const std::size_t k = std::size_t(offsets[q + 1] - offsets[q]);
      if (k > 0) std::memcpy(indices + offsets[q], src, k * sizeof(std::int32_t));  // src is null for an empty chunk
      src += k;
    }
  });
}

}  // namespace

template <typename T>
void GridNeighborSearch<T>::run(const Vec3<T>* queries, std::size_t nq, const std::vector<T>& radii, bool self,
                                bool storage, NeighborLists& out) const {
  checkQueries(queries, nq, radii, self);

  // Every entry of offsets and indices is written below: resizing a reused `out` to the same sizes writes
  // nothing, and nothing is zeroed twice.
  out.offsets.resize(nq + 1);
  out.offsets[0] = 0;
  QueryJob<T> job;
  job.g = view();
  job.xs = slot_x_.data();
  job.ys = slot_y_.data();
  job.zs = slot_z_.data();
  // Storage-order lists name slots, original-order lists original indices (the fast path's id array).
  job.ids = storage ? slot_store_.data() : slot_orig_.data();
  job.perm = storage ? nullptr : perm_.data();
  job.queries = self ? nullptr : queries;
  job.radii = radii.data();
  job.per_query = radii.size() == nq && nq > 1;
  // Storage-order lists in bucket order: the fast path visits rows (z, then y) and each row's slots in
  // ascending bucket order, which is the storage order, so its rows come out sorted.
  job.sort_rows = !(storage && entries_.empty());
  job.counts = out.offsets.data() + 1;
  // Rows of query i land in row q = perm[i] for original-order self-queries, else in row i (contiguous per block).
  const bool scattered = self && !storage;

  // One pass: each block of queries (one per thread, in storage order for self-queries, for locality) appends
  // its sorted rows to its own buffer and records their lengths; a prefix sum places the buffers. The GPU
  // counts first instead, because it cannot grow buffers; the lists are the same.
  const QueryBlocks qb{std::max<std::int64_t>(1, std::min<std::int64_t>(std::int64_t(nq), threadCount())), nq};
  std::unique_lock<std::mutex> lock(scratch_.mutex, std::try_to_lock);
  std::vector<detail::IndexBuffer> own;
  std::vector<detail::IndexBuffer>& buffers = lock.owns_lock() ? scratch_.blocks : own;
  if (buffers.size() < std::size_t(qb.count)) buffers.resize(std::size_t(qb.count));
  bool failed = !queryAllBlocks(job, qb, buffers);
  std::vector<std::int64_t> block_base(std::size_t(qb.count) + 1, 0);
  for (std::int64_t b = 0; b < qb.count; ++b)
    block_base[std::size_t(b) + 1] = block_base[std::size_t(b)] + std::int64_t(buffers[std::size_t(b)].size);
  if (!failed) {
    try {
      out.indices.resize(std::size_t(block_base[std::size_t(qb.count)]));
    } catch (const std::bad_alloc&) {
      failed = true;
    }
  }
  if (failed) {  // never truncate: either every list is complete or the caller gets an error
    for (detail::IndexBuffer& buf : buffers) buf = detail::IndexBuffer{};
    throw InputError(
        "", "radius",
        "the neighbour lists of " + std::to_string(nq) + " queries do not fit in memory; use a smaller radius");
  }
  if (scattered)
    placeScatteredRows(qb, perm_, buffers, out);
  else
    placeBlockRows(qb, block_base, buffers, out);
}

void setNeighborScanPortable(bool portable_only) { g_scan_portable_only = portable_only; }

bool neighborScanUsesAvx2() { return !g_scan_portable_only && cpuHasAvx2(); }

namespace detail {
std::int32_t* IndexBuffer::room(std::size_t extra) {
  if (size + extra > capacity) {
    const std::size_t grown = std::max(size + extra, capacity + capacity / 2 + 64);
    std::unique_ptr<std::int32_t[]> bigger(new std::int32_t[grown]);  // not value-initialised
    if (size) std::memcpy(bigger.get(), data.get(), size * sizeof(std::int32_t));
    data = std::move(bigger);
    capacity = grown;
  }
  return data.get() + size;
}
}  // namespace detail

template class GridNeighborSearch<float>;
template class GridNeighborSearch<double>;

}  // namespace inc::cpu
