// Per-element bodies of the sort-based adjacency and PBD constraint rebuild of a torn sheet, shared by the CPU reference and the CUDA kernels.
#pragma once

#include <cstdint>

#include "physics/hd.h"
#include "physics/pbd_constraints.h"
#include "physics/vec3.h"

namespace inc::tear {

// The rebuild sorts packed keys (radix sort on the device, std::stable_sort in the CPU reference). A particle
// index takes `bits` bits (indexBits of the particle count), an edge key 2 * bits: (min << bits) | max, so that
// ascending keys are the host rebuild's (a, b) order with a < b.
INC_HD int indexBits(std::int64_t n) {
  int b = 1;
  while (b < 31 && (std::int64_t(1) << b) <= n) ++b;
  return b;
}

INC_HD std::uint64_t packEdge(std::int32_t a, std::int32_t b, int bits) {
  const std::uint32_t lo = std::uint32_t(a < b ? a : b), hi = std::uint32_t(a < b ? b : a);
  return (std::uint64_t(lo) << bits) | std::uint64_t(hi);
}
INC_HD std::int32_t edgeHigh(std::uint64_t key, int bits) { return std::int32_t(key >> bits); }
INC_HD std::int32_t edgeLow(std::uint64_t key, int bits) {
  return std::int32_t(key & ((std::uint64_t(1) << bits) - 1));
}

// Half-edge h of the triangle list (triangle h / 3, corner h % 3): the edge tri[c] - tri[c+1] and the vertex
// opposite it (the bending wing across this edge).
INC_HD void halfEdge(const std::int32_t* tris, std::int64_t h, int bits, std::uint64_t& key, std::int32_t& opp) {
  const std::int32_t* t = tris + 3 * (h / 3);
  const int c = int(h % 3);
  key = packEdge(t[c], t[(c + 1) % 3], bits);
  opp = t[(c + 2) % 3];
}

// Over sorted half-edge keys: h starts a run of equal keys (a unique edge); its run length is the number of
// triangles on the edge (1 boundary, 2 interior: one bending constraint, > 2 non-manifold: none).
INC_HD bool runHead(const std::uint64_t* keys, std::int64_t h) { return h == 0 || keys[h] != keys[h - 1]; }
INC_HD int runLength(const std::uint64_t* keys, std::int64_t h, std::int64_t total) {
  int m = 1;
  while (h + m < total && keys[h + m] == keys[h]) ++m;
  return m;
}

// First position q in ascending keys[0 .. n) with keys[q] >= v (n when none): CSR offsets from sorted owners.
template <typename K>
INC_HD std::int64_t lowerBound(const K* keys, std::int64_t n, K v) {
  std::int64_t lo = 0, hi = n;
  while (lo < hi) {
    const std::int64_t mid = lo + (hi - lo) / 2;
    if (keys[mid] < v)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}

// Writes unique edge e (the run starting at sorted half-edge h) as distance constraint e, and, when the edge
// has exactly two triangles, bending constraint c (wings ascending). Rest values from rest positions, exactly
// as buildTearPbdModel computes them.
template <typename T>
INC_HD void writeEdgeConstraints(const std::uint64_t* keys, const std::int32_t* opp, std::int64_t h, int run,
                                 int bits, std::int64_t e, std::int64_t c, const Vec3<T>* rest, T stretch_compliance,
                                 T bending_compliance, std::int32_t* edge_a, std::int32_t* edge_b,
                                 std::int32_t* dist_ids, T* dist_rest, T* dist_compliance, std::int32_t* bend_ids,
                                 T* bend_rest, T* bend_compliance) {
  const std::int32_t a = edgeHigh(keys[h], bits), b = edgeLow(keys[h], bits);
  if (edge_a) edge_a[e] = a;
  if (edge_b) edge_b[e] = b;
  dist_ids[2 * e] = a;
  dist_ids[2 * e + 1] = b;
  dist_rest[e] = norm(rest[a] - rest[b]);
  dist_compliance[e] = stretch_compliance;
  if (run != 2 || !bend_ids) return;
  const std::int32_t w0 = opp[h], w1 = opp[h + 1];
  const std::int32_t p2 = w0 < w1 ? w0 : w1, p3 = w0 < w1 ? w1 : w0;
  bend_ids[4 * c] = a;
  bend_ids[4 * c + 1] = b;
  bend_ids[4 * c + 2] = p2;
  bend_ids[4 * c + 3] = p3;
  bend_rest[c] = pbd::dihedralAngle(rest[a], rest[b], rest[p2], rest[p3]);
  bend_compliance[c] = bending_compliance;
}

// Jacobi scale of constraint c of a fixed-arity block: 1 / (this block's constraints on its busiest movable
// participant), at least 1 constraint (finalizePbdModel's rule; w == 0 marks a fixed particle).
template <typename T>
INC_HD T jacobiScaleOf(const std::int32_t* ids, int arity, std::int64_t c, const std::int32_t* particle_offsets,
                       const T* inv_mass) {
  int busiest = 1;
  for (int k = 0; k < arity; ++k) {
    const std::int32_t p = ids[arity * c + k];
    if (!(inv_mass[p] > T(0))) continue;
    const int deg = particle_offsets[p + 1] - particle_offsets[p];
    busiest = deg > busiest ? deg : busiest;
  }
  return T(1) / T(busiest);
}

}  // namespace inc::tear
