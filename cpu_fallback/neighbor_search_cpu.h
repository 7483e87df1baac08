// CPU uniform-grid fixed-radius neighbour search (the CUDA search's algorithm, looped with parallelFor).
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "model/neighbor_lists.h"
#include "physics/neighbor_grid.h"
#include "physics/vec3.h"

namespace inc::cpu {

// The candidate scan of the dense fast path: AVX2 where the CPU has it (checked at run time; 8 floats or 4
// doubles per step), else the portable one (SSE2 on x86-64, plain C++ elsewhere). Identical lists either way;
// forcing the portable scan lets tests compare both on one machine.
void setNeighborScanPortable(bool portable_only);
bool neighborScanUsesAvx2();

namespace detail {
// A growable int32 array that does not value-initialise what it adds (std::vector would zero every entry,
// and rows are written right after).
struct IndexBuffer {
  std::unique_ptr<std::int32_t[]> data;
  std::size_t size = 0, capacity = 0;
  std::int32_t* room(std::size_t extra);  // capacity for size + extra entries; returns data + size
  void push(std::int32_t v) { room(1)[0] = v, ++size; }
};
// The row buffers of the query blocks, kept between calls so that a repeated query writes into memory it
// already owns instead of paging in fresh buffers. A copy of the search starts without them; a query that
// finds them in use by another thread uses buffers of its own.
struct QueryScratch {
  std::mutex mutex;
  std::vector<IndexBuffer> blocks;
  QueryScratch() = default;
  QueryScratch(const QueryScratch&) {}
  QueryScratch& operator=(const QueryScratch&) { return *this; }
};
}  // namespace detail

// Build once per point configuration, query many times. Lists follow model/neighbor_lists.h: per query,
// ascending original point index, closed ball (d^2 <= r^2 via distance2Exact), self-queries leave q out.
// Bad input (non-finite point, query or radius; cell size <= 0) throws InputError naming the entry.
template <typename T>
class GridNeighborSearch {
 public:
  GridNeighborSearch() = default;
  GridNeighborSearch(const std::vector<Vec3<T>>& points, T cell_size, bool morton_order = false) {
    build(points, cell_size, morton_order);
  }

  // cell_size: edge of a grid cell; the usual choice is the (largest) query radius. Any radius works with
  // any cell size (larger radii search more cells). morton_order: store the points in Z order of their cells.
  void build(const std::vector<Vec3<T>>& points, T cell_size, bool morton_order = false);

  // Every point against every other point, one radius for all, or radii[i] for point i (size 1 or n).
  NeighborLists querySelf(T radius) const;
  NeighborLists querySelf(const std::vector<T>& radii) const;
  // Each query also exists writing into `out`, reusing its storage: a repeated query of about the same size
  // allocates nothing and pages in no fresh memory (what a simulation that rebuilds its lists every step wants).
  void querySelf(T radius, NeighborLists& out) const;
  void querySelf(const std::vector<T>& radii, NeighborLists& out) const;
  // Every point against every other point in storage order (the space of sortedPoints()): row s lists the
  // storage slots of slot s's neighbours, ascending. The same pairs as querySelf, with no permutation applied;
  // callers that keep their particle arrays in storage order use it directly (map back with sortedToOriginal()).
  NeighborLists querySelfStorage(T radius) const;
  void querySelfStorage(T radius, NeighborLists& out) const;
  // Another point set (e.g. tool samples) against the built points; radii of size 1 or queries.size().
  NeighborLists query(const std::vector<Vec3<T>>& queries, const std::vector<T>& radii) const;
  NeighborLists query(const std::vector<Vec3<T>>& queries, T radius) const;
  void query(const std::vector<Vec3<T>>& queries, const std::vector<T>& radii, NeighborLists& out) const;
  void query(const std::vector<Vec3<T>>& queries, T radius, NeighborLists& out) const;

  std::size_t size() const { return sorted_.size(); }
  T cellSize() const { return cell_size_; }
  bool mortonOrder() const { return morton_; }
  bool hashed() const { return !sorted_.empty() && params_.dense == 0; }
  const NeighborGridParams<T>& params() const { return params_; }
  // Storage order: slot s holds original point sortedToOriginal()[s]; originalToSorted() is its inverse.
  // With morton_order the storage order is the Z order of the cells (use it to reorder particle arrays).
  const std::vector<std::int32_t>& sortedToOriginal() const { return perm_; }
  const std::vector<std::int32_t>& originalToSorted() const { return inv_perm_; }
  const std::vector<Vec3<T>>& sortedPoints() const { return sorted_; }

 private:
  // self: queries are the built points; storage: rows and indices in storage order (self only).
  void run(const Vec3<T>* queries, std::size_t nq, const std::vector<T>& radii, bool self, bool storage,
           NeighborLists& out) const;
  NeighborGridView<T> view() const;

  T cell_size_ = T(0);
  bool morton_ = false;
  NeighborGridParams<T> params_{};
  std::vector<Vec3<T>> sorted_;             // points in storage order
  std::vector<std::int32_t> perm_;          // storage slot -> original index
  std::vector<std::int32_t> inv_perm_;      // original index -> storage slot
  std::vector<std::int32_t> bucket_start_;  // occupied cells (dense grid) or buckets (hashed) + 1
  std::vector<std::int32_t> entries_;       // Morton mode: storage index per bucket slot (else empty)
  // The points in bucket-slot order as separate coordinate arrays plus their original indices: the dense
  // fast path of the query streams these (one contiguous run of slots per (y, z) row of cells). Each carries
  // a few padding entries past n, which the vector scan may read (masked off).
  std::vector<T> slot_x_, slot_y_, slot_z_;
  std::vector<std::int32_t> slot_orig_;
  std::vector<std::int32_t> slot_store_;  // storage slot of each bucket slot (identity unless Morton)
  std::vector<std::uint32_t> keys_;       // build scratch: each point's bucket (kept: no fresh pages per build)
  mutable detail::QueryScratch scratch_;
};

}  // namespace inc::cpu
