// Host launch wrappers of the per-particle PBD kernels (kernels/pbd_particle_kernels.cu): prediction, kinematic
// targets, velocities, sphere radii.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "physics/pbd_collision.h"
#include "physics/vec3.h"

namespace inc::cuda {

// Each launches its kernel with `blocks` blocks of kThreads on `stream` and checks the launch. The kernels live in
// one translation unit (no relocatable device code): other files launch them through these.
template <typename T>
struct PbdParticleKernels {
  // pbd::predictParticle of particles [0, live count); cheb_x1 (Chebyshev) receives the substep's first iterate.
  static void predict(unsigned blocks, cudaStream_t stream, int n, const int* live_n, Vec3<T>* x, Vec3<T>* v,
                      Vec3<T>* x_prev, const T* w, Vec3<T> g, T damp, T dt, Vec3<T>* cheb_x1);
  // x[ids[q]] := lerp(from[q], to[q], t) for the k kinematic particles.
  static void kinematic(unsigned blocks, cudaStream_t stream, int k, Vec3<T>* x, const std::int32_t* ids,
                        const Vec3<T>* from, const Vec3<T>* to, T t);
  // from[q] := x[ids[q]]: the kinematic particles' start positions, gathered on the device.
  static void gatherKinematic(unsigned blocks, cudaStream_t stream, int k, const Vec3<T>* x, const std::int32_t* ids,
                              Vec3<T>* from);
  // w[ids[q]] := 0: the frame's inverse masses of the kinematic particles.
  static void zeroKinematic(unsigned blocks, cudaStream_t stream, int k, T* w, const std::int32_t* ids);
  // v := (x - x_prev) inv_dt for particles [0, live count).
  static void velocity(unsigned blocks, cudaStream_t stream, int n, const int* live_n, const Vec3<T>* x,
                       const Vec3<T>* x_prev, Vec3<T>* v, T inv_dt);
  // active[i]: whether sphere i's radius is solved this frame (all when influence < 0, else near a tool).
  static void volumeActive(unsigned blocks, cudaStream_t stream, int n, const Vec3<T>* x, const T* rest_r,
                           const pbd::CapsuleCollider<T>* tools_to, int nt, T influence, std::uint8_t* active);
  // One Jacobi pass of the radius solve (pbd::radiusForCellVolume) into radii_next.
  static void radius(unsigned blocks, cudaStream_t stream, int n, const Vec3<T>* x, const T* radii, T* radii_next,
                     const T* rest_r, const T* rest_cell, const std::int32_t* ov_off, const std::int32_t* ov_ids,
                     const Vec3<T>* samples, int sample_count, const std::uint8_t* active, T growth,
                     int bisection_steps);
  // radii := rest radii for particles [0, live count).
  static void restRadii(unsigned blocks, cudaStream_t stream, int n, const int* live_n, T* radii, const T* rest_r);
};

}  // namespace inc::cuda
