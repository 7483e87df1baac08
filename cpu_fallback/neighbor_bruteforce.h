// O(N*M) fixed-radius search: the oracle the grid searches are tested against, and a fallback for tiny sets.
#pragma once

#include <vector>

#include "model/neighbor_lists.h"
#include "physics/vec3.h"

namespace inc::cpu {

// Each query against every point; radius per query when radii.size() == queries.size(), else radii[0].
// self == true means queries and points are the same set and q does not list itself.
template <typename T>
NeighborLists bruteForceNeighbors(const std::vector<Vec3<T>>& queries, const std::vector<Vec3<T>>& points,
                                  const std::vector<T>& radii, bool self);

}  // namespace inc::cpu
