// CUDA uniform-grid fixed-radius neighbour search (device-resident grid and CSR lists; same lists as the CPU).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "kernels/device_buffer.h"
#include "model/neighbor_lists.h"
#include "physics/neighbor_grid.h"
#include "physics/vec3.h"

namespace inc::cuda {

// 16-byte aligned record of a float point for the query kernels (float4 layout; host code needs no CUDA types).
template <typename T>
struct alignas(4 * sizeof(T)) Packed4 {
  T v[4];
};

// Device copy of model/neighbor_lists.h: row q is indices[offsets[q] .. offsets[q + 1]), ascending original
// point index, closed ball (distance2Exact <= r * r), self-queries leave q out.
struct DeviceNeighborLists {
  DeviceBuffer<std::int64_t> offsets;  // queries + 1
  DeviceBuffer<std::int32_t> indices;  // offsets[queries] entries
  std::size_t queryCount() const { return offsets.size() == 0 ? 0 : offsets.size() - 1; }
  NeighborLists download() const;
};

// The grid parameters as the device writes them for the host: the parameters and the first non-finite point.
template <typename T>
struct GridParamsReadback {
  NeighborGridParams<T> p;
  Vec3<T> bad;  // points[p.first_bad] when p.first_bad < n
};

// Build once per point configuration, query many times. Everything runs on the default stream.
// Host synchronisations (each one device-to-host copy of a few bytes, documented in docs/neighbor-search.md):
//  - build(d_points): none (bucket order). The grid parameters (bounding box reduced on the device) are
//    copied back asynchronously; the cell table and the radix-sort key width are sized for the largest grid
//    the point count allows, so nothing waits for them. The host reads them when it first needs them: the
//    next query (which waits anyway for its total), params(), hashed(), bucketTableSize() or check(), and
//    that is where a non-finite point is reported (InputError naming points[i]). Morton order waits for
//    them inside build (the Z-order key width depends on the grid's extent) and reports there.
//  - build(host vector): uploads (synchronous) and checks before returning, as before.
//  - each query: one, reading back the total neighbour count (to allocate the index array exactly, so no
//    list is ever truncated) together with the first invalid query point / radius found on the device.
// Not thread-safe: queries share scratch buffers of the object.
template <typename T>
class GridNeighborSearch {
 public:
  GridNeighborSearch() = default;

  // d_points: n positions in device memory (read during build only; the grid keeps its own sorted copy).
  // cell_size: edge of a grid cell, usually the (largest) query radius; any radius works with any cell size.
  // morton_order: store the points in Z order of their cells (sortedToOriginal() maps back).
  // Throws InputError for a bad cell size or count at once, and names points[i], the first non-finite point,
  // at the next call that reads the grid on the host (see above; at once with morton_order).
  void build(const Vec3<T>* d_points, std::size_t n, T cell_size, bool morton_order = false);
  // Convenience: uploads host points, then builds and checks (throws here for a non-finite point).
  void build(const std::vector<Vec3<T>>& points, T cell_size, bool morton_order = false);
  // Waits for the last build's grid parameters; throws InputError naming the first non-finite point (the
  // grid is then empty). Queries call it themselves.
  void check() const { ensureParams(); }

  // Every built point against every other point; one radius, or d_radii[count] on the device (count 1 or n).
  DeviceNeighborLists querySelf(T radius) const;
  void querySelf(T radius, DeviceNeighborLists& out) const;  // reuses out's buffers (they never shrink)
  void querySelf(const T* d_radii, std::size_t radii_count, DeviceNeighborLists& out) const;
  // Storage-order self-query (the space of sortedPoints()): row s lists the storage slots of slot s's
  // neighbours, ascending; the same pairs as querySelf, with no permutation applied (map back with
  // sortedToOriginal()). The cheapest form: one traversal writes every row straight to its place (tile offsets
  // from a decoupled look-back scan inside the kernel); out.indices is sized optimistically from its capacity
  // (at least 32 per query) and, if the lists are longer, grown to the exact total and filled by a second run.
  // One host read of the total per call (two after a growth). Same lists as cpu::querySelfStorage.
  void querySelfStorage(T radius, DeviceNeighborLists& out) const;
  // nq device query points (e.g. tool samples) against the built points.
  DeviceNeighborLists query(const Vec3<T>* d_queries, std::size_t nq, T radius) const;
  void query(const Vec3<T>* d_queries, std::size_t nq, T radius, DeviceNeighborLists& out) const;
  void query(const Vec3<T>* d_queries, std::size_t nq, const T* d_radii, std::size_t radii_count,
             DeviceNeighborLists& out) const;

  std::size_t size() const { return n_ + pending_n_; }
  T cellSize() const { return cell_size_; }
  bool mortonOrder() const { return morton_; }
  bool hashed() const {
    ensureParams();
    return n_ > 0 && params_.dense == 0;
  }
  // Host copy of the grid parameters (waits for the build's read-back).
  const NeighborGridParams<T>& params() const {
    ensureParams();
    return params_;
  }
  // Device arrays of size(): storage slot -> original index, its inverse, and the points in storage order.
  // The build writes what the queries read (the permutation; the points as float4 records for float, as
  // Vec3 for double); the inverse permutation and, for float, the Vec3 copy are made on the first request
  // after a build (one kernel on the default stream), so a build + query pays for neither.
  const std::int32_t* sortedToOriginal() const { return perm_.data(); }
  const std::int32_t* originalToSorted() const;
  const Vec3<T>* sortedPoints() const;
  // Cell-table entries actually used (occupied-cell box for dense grids, bucket count for hashed ones).
  std::size_t bucketTableSize() const {
    ensureParams();
    return used_buckets_;
  }

  // Per-stage device timing for benchmarks (CUDA events between the stages of build and query). Off by
  // default: nothing is recorded and no synchronisation is added. takeProfile() waits for the last event and
  // returns (stage, milliseconds) for every stage recorded since the previous takeProfile(), then forgets them.
  // Queries stage rows of up to 48 neighbours during the count pass (48 x 4 bytes per query of scratch), so the
  // neighbourhoods are traversed once; above this many scratch bytes they fall back to count + re-traverse.
  // Default 4 GiB (1.6e7 queries need 3.1 GB); 0 forces the two-pass path (tests use it to cover both).
  void setStagingLimitBytes(std::size_t bytes) { staged_limit_bytes_ = bytes; }
  void setProfiling(bool on) {
    profiling_ = on;
    marks_.clear();
  }
  std::vector<std::pair<std::string, double>> takeProfile() const;

 private:
  void run(const Vec3<T>* d_queries, std::size_t nq, T radius, const T* d_radii, std::size_t radii_count, bool self,
           DeviceNeighborLists& out) const;
  void* scratch(std::size_t bytes) const;
  void mark(const char* stage) const;  // records an event named after the stage that ends here (profiling only)
  void ensureParams() const;           // host copy of the parameters from the pinned read-back; the non-finite check
  void enqueueBuild(const Vec3<T>* d_points, std::size_t n, std::uint32_t buckets, struct CUstream_st* stream);

  // What a captured build graph depends on: its inputs and every buffer it touches.
  struct BuildGraphKey {
    std::array<const void*, 15> ptrs{};
    std::size_t n = 0;
    T cell = T(0);
    bool operator==(const BuildGraphKey& o) const { return ptrs == o.ptrs && n == o.n && cell == o.cell; }
  };

  // A build whose parameters the host has not read yet holds its point count in pending_n_ (n_ is 0 until
  // ensureParams has checked the points), so size() is right either way.
  mutable std::size_t n_ = 0, pending_n_ = 0;
  T cell_size_ = T(0);
  bool morton_ = false;
  mutable std::size_t used_buckets_ = 0;
  mutable NeighborGridParams<T> params_{};
  DeviceBuffer<Vec3<T>> upload_;  // host-vector build only
  DeviceBuffer<GridParamsReadback<T>> d_params_;
  std::shared_ptr<void> pinned_params_;  // GridParamsReadback<T> in page-locked host memory
  std::shared_ptr<void> params_event_;   // cudaEvent_t: the read-back has landed
  std::shared_ptr<void> stream_;         // cudaStream_t of the builds (blocking: ordered with stream 0)
  std::shared_ptr<void> side_stream_, fork_event_, join_event_;  // the read-back's branch of a build
  const void* iota_for_ = nullptr;     // iota_ holds 0, 1, 2, ... (written once per allocation)
  std::shared_ptr<void> build_graph_;  // cudaGraphExec_t of the last bucket-order build
  BuildGraphKey build_key_;
  mutable DeviceBuffer<Vec3<T>> sorted_;  // points in storage order (float: made on request)
  mutable bool sorted_ready_ = false, inverse_ready_ = false;
  DeviceBuffer<Packed4<T>> packed_;              // float only: the same points as 16-byte records (x, y, z, 0)
  DeviceBuffer<std::int32_t> perm_;              // slot -> original
  mutable DeviceBuffer<std::int32_t> inv_perm_;  // original -> slot (made on request)
  DeviceBuffer<std::int32_t> bucket_start_;      // used_buckets_ + 1
  DeviceBuffer<std::int32_t> cell_count_;        // used_buckets_ + 1 (histogram before the scan)
  DeviceBuffer<std::int32_t> entries_;           // Morton mode: storage slot per bucket-ordered entry
  DeviceBuffer<std::uint32_t> keys_, keys_sorted_;
  DeviceBuffer<std::int32_t> iota_;
  mutable DeviceBuffer<std::int32_t> counts_;  // per query
  mutable DeviceBuffer<std::int32_t> staged_;  // fused query: sorted short rows, kRowCap per storage slot
  std::size_t staged_limit_bytes_ = std::size_t(4) << 30;
  mutable DeviceBuffer<std::uint64_t> status_;       // {first bad query, first bad radius, total}
  mutable DeviceBuffer<std::uint64_t> tile_status_;  // storage query: look-back words per tile + tile counter
  mutable DeviceBuffer<unsigned char> temp_;         // CUB temporary storage
  DeviceBuffer<Vec3<T>> partial_lo_, partial_hi_;    // bounding-box partials per block
  DeviceBuffer<std::int64_t> partial_bad_;
  bool profiling_ = false;
  mutable std::vector<std::pair<std::string, std::shared_ptr<void>>> marks_;  // cudaEvent_t, destroyed by the deleter
};

}  // namespace inc::cuda
