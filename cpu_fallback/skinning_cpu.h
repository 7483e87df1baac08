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
void vertexNormalsCpu(int vertex_count, const Vec3<T>* x, const std::int32_t* triangles,
                      const std::int32_t* tri_offsets, const std::int32_t* tri_of_vertex, Vec3<T>* normals);

// Per-sphere rotations from the neighbourhoods' deformation: quats (warm start in, result out, one per sphere)
// and rotations[i] = the matrix of quats[i]. x: current centres, x0: rest centres.
template <typename T>
void sphereRotationsCpu(int sphere_count, const Vec3<T>* x, const Vec3<T>* x0, const T* mass, const std::int32_t* off,
                        const std::int32_t* nbr, int iterations, pbd::Quat<T>* quats, Mat3<T>* rotations);

// rotations[i] = matrix of quats[i] (the PBD state keeps per-particle rotations as quaternions).
template <typename T>
void quatsToMatricesCpu(int n, const pbd::Quat<T>* quats, Mat3<T>* rotations);

}  // namespace inc::cpu
