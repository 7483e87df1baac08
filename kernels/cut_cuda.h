// CUDA per-element cut tests: which spheres the swept surface enters, which neighbour pairs cross it.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "physics/vec3.h"

namespace inc::cuda {

// One thread per sphere: 1 when the swept triangles enter its open ball (cut::sphereTouchesTriangle), else 0.
// swept_vertices / swept_triangles are the SweptSurface arrays. Same double arithmetic as the CPU path.
std::vector<std::uint8_t> cutSphereMaskCuda(const std::vector<Vec3d>& swept_vertices,
                                            const std::vector<std::array<int, 3>>& swept_triangles,
                                            const std::vector<Vec3d>& centres, const std::vector<double>& radii);

// One thread per neighbour entry of CSR lists: 1 when the pair's segment crosses a swept triangle
// (cut::segmentCrossesTriangle), the visibility criterion.
std::vector<std::uint8_t> crossingPairMaskCuda(const std::vector<Vec3d>& swept_vertices,
                                               const std::vector<std::array<int, 3>>& swept_triangles,
                                               const std::vector<Vec3d>& positions,
                                               const std::vector<std::int64_t>& offsets,
                                               const std::vector<std::int32_t>& indices);

}  // namespace inc::cuda
