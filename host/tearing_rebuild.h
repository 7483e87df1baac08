// Sort-based rebuild of a torn sheet's adjacency and PBD constraints (the device algorithm, run on the CPU as its reference).
#pragma once

#include <cstdint>
#include <vector>

#include "host/pbd_model.h"
#include "host/tearing_sheet.h"

namespace inc {

// What the device rebuild (kernels/tearing_cuda.cu) derives from the triangles after a tearing step. Equal,
// array for array, to TearSheet::rebuildTopology() followed by buildTearPbdModel(coloring = false): the
// blocks' ids, offsets, rest values, particle -> slot CSR and Jacobi scales (colouring left empty).
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

}  // namespace inc
