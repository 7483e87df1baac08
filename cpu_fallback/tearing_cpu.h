// CPU tearing step: yield detection, independent-set selection, prefix-sum compaction, vertex split with debris, triangle rebuild.
#pragma once

#include <cstdint>
#include <vector>

#include "host/tearing_sheet.h"

static_assert(sizeof(std::array<std::int32_t, 3>) == 3 * sizeof(std::int32_t), "triangles are read as int32 triples");

namespace inc::cpu {

struct TearStepStats {
  int yielding = 0;        // particles past the criterion whose split is possible
  int splits = 0;          // particles split this step (= new particles)
  int deferred = 0;        // yielding but sharing a triangle with a higher-priority yielding particle
  int moved_triangles = 0; // triangles moved from split particles to their new particles
  int backed_off = 0;      // splits whose fraction t was reduced to keep triangles valid
};

// Per-particle results of the detection pass (kept for tests and the GPU parity check).
template <typename T>
struct TearCandidates {
  std::vector<std::uint8_t> yield;      // criterion passed and the split separates triangles
  std::vector<std::uint8_t> accept;     // in this step's independent set
  std::vector<std::int32_t> partner;    // j: the broken bond's other particle
  std::vector<Vec3<T>> dir;             // crack-opening direction (split plane normal), towards j
  std::vector<T> t_pred;                // predicted fraction before the random perturbation
};

// One tearing step on sheet `s` (positions/velocities current). Phases, each a parallel loop:
//  1 per particle: bond-strain extrema (or bond stress tensor), criterion, split side counts;
//  2 per particle: accept when no higher-priority yielding particle shares a triangle (gather);
//  3 exclusive prefix sum of accept -> new particle index n = N + rank;
//  4 per accepted particle: fraction t (seeded), back-off to keep triangles valid, new particle's data;
//  5 per triangle: the vertex of an accepted particle on the crack side becomes its new particle.
// Then the adjacency is rebuilt (unless rebuild == false: the caller rebuilds it with the model).
// Deterministic for any thread count.
template <typename T>
TearStepStats tearStepCpu(TearSheet<T>& s, const TearParams<T>& p, TearCandidates<T>* out = nullptr,
                          bool rebuild = true);

}  // namespace inc::cpu
