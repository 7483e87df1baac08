// Skinning math shared by CPU and GPU: distance-field weights, linear blend of sphere motions, vertex normals.
#pragma once

#include <cstdint>

#include "physics/hd.h"
#include "physics/pbd_rotation.h"
#include "physics/vec3.h"

namespace inc::skin {

// Weight of a sphere whose surface is `e` farther from the vertex than the nearest sphere's surface, when the
// first sphere not bound to the vertex is `rho` farther: w = (1 - e / rho)^2 for e < rho, else 0.
// The weight is a smooth function of the distance field d_i = |v - c_i| - r_i (the signed distance to sphere
// i) and falls to zero exactly where a sphere leaves the k nearest, so weights vary continuously over the
// surface (no seams where the bound set changes). Normalised by the caller to a partition of unity.
template <typename T>
INC_HD T bindWeight(T e, T rho) {
  if (!(rho > T(0))) return T(1);  // all candidates equally near: equal weights after normalisation
  const T s = T(1) - e / rho;
  return s > T(0) ? s * s : T(0);
}

// Device-friendly view of a skin binding (structure of arrays, k slots per vertex, slot-major per vertex:
// entry v * k + j). Unused slots have weight 0 (and a valid sphere index).
template <typename T>
struct SkinView {
  int vertex_count = 0;
  int k = 0;
  const Vec3<T>* rest_vertices = nullptr;  // surface at rest, m
  const std::int32_t* sphere = nullptr;    // bound sphere per slot
  const T* weight = nullptr;               // per slot, sum 1 per vertex
  const Vec3<T>* rest_centres = nullptr;   // sphere centres at rest, m
};

// Linear blend skinning of one vertex: x = sum_j w_j (R_j (x0 - c0_j) + c_j), with the sphere's rotation R_j
// (identity when `rotations` is null) and current centre c_j. Reproduces any rigid motion applied to all
// spheres exactly (sum w_j = 1), and the rest surface exactly at rest.
template <typename T>
INC_HD Vec3<T> skinVertex(const SkinView<T>& s, int v, const Vec3<T>* centres, const Mat3<T>* rotations) {
  const Vec3<T> x0 = s.rest_vertices[v];
  Vec3<T> x;
  for (int j = 0; j < s.k; ++j) {
    const int slot = v * s.k + j;
    const T w = s.weight[slot];
    if (w == T(0)) continue;
    const int i = s.sphere[slot];
    const Vec3<T> off = x0 - s.rest_centres[i];
    const Vec3<T> moved = rotations ? rotations[i] * off : off;
    x += (moved + centres[i]) * w;
  }
  return x;
}

// Area-weighted vertex normal (unit; zero when the incident triangles have no area), gathered from the
// vertex's incident triangles (CSR: triangles tri_of[off[v] .. off[v+1]), corners in `tris`, 3 per triangle).
template <typename T>
INC_HD Vec3<T> vertexNormal(int v, const Vec3<T>* x, const std::int32_t* tris, const std::int32_t* off,
                            const std::int32_t* tri_of) {
  Vec3<T> n;
  for (int m = off[v]; m < off[v + 1]; ++m) {
    const int t = tri_of[m];
    const Vec3<T> a = x[tris[3 * t]], b = x[tris[3 * t + 1]], c = x[tris[3 * t + 2]];
    n += cross(b - a, c - a);  // twice the area times the unit normal
  }
  const T l = norm(n);
  return l > T(0) ? n * (T(1) / l) : Vec3<T>{};
}

// Rotation of sphere i from its neighbourhood's deformation (shape matching): the moment matrix
// A = sum_j m_j (x_j - xbar)(x0_j - x0bar)^T over the sphere and its linked neighbours (CSR off/nbr), with
// mass-weighted centroids xbar, x0bar; R is the rotational part of A (polar decomposition, warm-started from
// the previous frame's quaternion `q`). Exact for any rigid motion of a neighbourhood that spans 3D.
template <typename T>
INC_HD pbd::Quat<T> sphereRotation(int i, const Vec3<T>* x, const Vec3<T>* x0, const T* mass, const std::int32_t* off,
                                   const std::int32_t* nbr, pbd::Quat<T> q, int iterations) {
  T msum = mass[i];
  Vec3<T> xbar = x[i] * mass[i], x0bar = x0[i] * mass[i];
  for (int m = off[i]; m < off[i + 1]; ++m) {
    const int j = nbr[m];
    msum += mass[j];
    xbar += x[j] * mass[j];
    x0bar += x0[j] * mass[j];
  }
  xbar *= T(1) / msum;
  x0bar *= T(1) / msum;
  Mat3<T> a = outer(x[i] - xbar, x0[i] - x0bar) * mass[i];
  for (int m = off[i]; m < off[i + 1]; ++m) {
    const int j = nbr[m];
    a += outer(x[j] - xbar, x0[j] - x0bar) * mass[j];
  }
  return pbd::extractRotation(a, q, iterations);
}

}  // namespace inc::skin
