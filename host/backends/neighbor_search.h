// One-call fixed-radius neighbour search on either backend (host vectors in, host CSR lists out).
#pragma once

#include <vector>

#include "model/backend.h"
#include "model/neighbor_lists.h"
#include "physics/vec3.h"

namespace inc {

struct NeighborSearchOptions {
  double cell_size = 0.0;     // grid cell edge; <= 0: CPU: half the largest radius if that grid is dense, else
                              // the largest radius; CUDA: the largest radius; 1 when every radius is 0
  bool morton_order = false;  // sort the grid's storage along the Z curve (same lists either way)
};

// Every point against every other point (self excluded), closed ball d <= radius, rows ascending by index.
// Cpu, Cuda or Auto (resolveBackend: Cuda without a usable device throws InputError). Both backends return
// identical lists. Bad input (non-finite point or radius) throws InputError naming the entry.
template <typename T>
NeighborLists findNeighbors(BackendKind backend, const std::vector<Vec3<T>>& points, T radius,
                            const NeighborSearchOptions& options = {});

// Each query point (e.g. a tool sample) against the points; radii has 1 entry or one per query.
template <typename T>
NeighborLists findNeighbors(BackendKind backend, const std::vector<Vec3<T>>& queries,
                            const std::vector<Vec3<T>>& points, const std::vector<T>& radii,
                            const NeighborSearchOptions& options = {});

}  // namespace inc
