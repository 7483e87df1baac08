// Rebuild of a torn sheet's adjacency and PBD constraints by the device algorithms (per-particle fans; the older
// radix-sort path), run on the CPU as their reference.
#pragma once

#include <cstdint>
#include <vector>

#include "model/pbd_model.h"
#include "model/tearing_sheet.h"
#include "physics/tearing_rebuild.h"

namespace inc {

// What the device rebuild (kernels/tearing_cuda.cu, either algorithm) derives from the triangles after a tearing step.
// Equal, array for array, to TearSheet::rebuildTopology() followed by buildTearPbdModel(coloring = false): the blocks'
// ids, offsets, rest values, particle -> slot CSR and Jacobi scales (colouring left empty).
template <typename T>
struct TearSortedRebuild {
  std::vector<std::int32_t> pt_offsets, pt_tris, edge_a, edge_b, pe_offsets, pe_partner;
  PbdConstraintBlock<T> distance, bending;
};

// The device algorithm with std::stable_sort in place of the radix sorts:
//  1 corners sorted by particle (stable) -> particle -> triangles CSR (offsets by binary search);
//  2 half-edges sorted by packed (min, max) key (physics/tearing_rebuild.h) -> unique edges (run heads), a
//    bending constraint on each run of length 2 (wings = the two opposite vertices), numbered by prefix sums;
//  3 both directions of every edge sorted by (owner, partner) -> particle -> partners CSR;
//  4 each block's slots sorted by particle (stable) -> particle -> slot CSR, then Jacobi scales.
template <typename T>
TearSortedRebuild<T> rebuildTearSorted(const TearSheet<T>& s, const TearModelOptions& opt);

// The per-particle algorithm (the device's default; physics/tearing_rebuild.h, "Per-particle rebuild"), no
// global sort:
//  1 corners counted per particle, exclusive scan -> offsets, corners scattered into their rows (in reverse
//    order here; the device's atomic cursors give any order), each row sorted -> particle -> triangles;
//  2 fanCounts per particle, exclusive scan over n + 1 entries (the totals last: the device's one read);
//  3 writeFanOffsets and writeFanEdges per particle: partner rows, edges, constraints, own distance slots;
//  4 writeLowerDistanceSlot per edge: the rest of the distance rows; the bending rows counted, scanned and
//    filled from the bending constraints (the device fills them through atomic cursors and sorts each row);
//  5 Jacobi scales per constraint (what PbdDevicePatch::commitBlockIncidence computes on the device).
// Precondition: no degenerate or duplicated triangle (checkTearMesh). fan_cache: the most triangles of a fan the
// register path takes (tear::FanPairs; tests pass 0 to force the global reads); the result never depends on it.
template <typename T>
TearSortedRebuild<T> rebuildTearFans(const TearSheet<T>& s, const TearModelOptions& opt,
                                     int fan_cache = tear::kFanPairs);

}  // namespace inc
