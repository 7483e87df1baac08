// CPU tearing step: yield detection, independent-set selection, prefix-sum compaction, vertex split with debris,
// triangle rebuild.
#pragma once

#include <cstdint>
#include <vector>

#include "model/tear_step.h"
#include "model/tearing_sheet.h"

static_assert(sizeof(std::array<std::int32_t, 3>) == 3 * sizeof(std::int32_t), "triangles are read as int32 triples");

namespace inc::cpu {

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
