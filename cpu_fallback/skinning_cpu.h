// CPU skinning: linear blend of sphere motions onto the surface and vertex normals, looped with parallelFor.
#pragma once

#include <cstdint>

#include "physics/skinning.h"

namespace inc::cpu {

// out[v] = skin::skinVertex(view, v, centres, rotations) for every vertex; rotations may be null (translation only).
template <typename T>
void skinSurfaceCpu(const skin::SkinView<T>& view, const Vec3<T>* centres, const Mat3<T>* rotations, Vec3<T>* out);

// normals[v] = skin::vertexNormal(v, ...) for v in [0, vertex_count).
template <typename T>
void vertexNormalsCpu(int vertex_count, const Vec3<T>* x, const std::int32_t* triangles, const std::int32_t* tri_offsets,
                      const std::int32_t* tri_of_vertex, Vec3<T>* normals);

}  // namespace inc::cpu
