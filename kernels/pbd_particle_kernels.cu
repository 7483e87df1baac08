// Per-particle PBD kernels of the per-block frame and their host launch wrappers: prediction, kinematic targets,
// velocities, sphere radii.
#include "kernels/pbd_particle_kernels.cuh"

#include <cstdint>

#include "kernels/cuda_check.h"
#include "kernels/pbd_launch.cuh"
#include "physics/pbd_block.h"
#include "physics/pbd_volume.h"

namespace inc::cuda {

namespace {

// Each kernel is one loop of the CPU backend (cpu_fallback/pbd_solver_cpu.cpp) with the same physics calls.

template <typename T>
__global__ void predictKernel(int n, const int* live_n, Vec3<T>* x, Vec3<T>* v, Vec3<T>* x_prev, const T* w, Vec3<T> g,
                              T damp, T dt, Vec3<T>* cheb_x1) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= liveCount(live_n, n)) return;
  pbd::predictParticle(x[i], v[i], x_prev[i], w[i], g, damp, dt);
  if (cheb_x1) cheb_x1[i] = x[i];  // Chebyshev: the substep's first iterate
}

template <typename T>
__global__ void kinematicKernel(int k, Vec3<T>* x, const std::int32_t* ids, const Vec3<T>* from, const Vec3<T>* to,
                                T t) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q >= k) return;
  x[ids[q]] = pbd::lerp(from[q], to[q], t);
}

template <typename T>
__global__ void gatherKinematicKernel(int k, const Vec3<T>* x, const std::int32_t* ids, Vec3<T>* from) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q < k) from[q] = x[ids[q]];
}

// A frame's inverse masses: kinematic particles get w = 0.
template <typename T>
__global__ void zeroKinematicKernel(int k, T* w, const std::int32_t* ids) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q >= k) return;
  w[ids[q]] = T(0);
}

template <typename T>
__global__ void velocityKernel(int n, const int* live_n, const Vec3<T>* x, const Vec3<T>* x_prev, Vec3<T>* v,
                               T inv_dt) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= liveCount(live_n, n)) return;
  v[i] = (x[i] - x_prev[i]) * inv_dt;
}

// Spheres whose radius is solved this frame: all (influence < 0) or those within influence of a tool.
template <typename T>
__global__ void volumeActiveKernel(int n, const Vec3<T>* x, const T* rest_r, const pbd::CapsuleCollider<T>* tools_to,
                                   int nt, T influence, std::uint8_t* active) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  std::uint8_t a = influence < T(0) ? 1 : 0;
  for (int k = 0; k < nt && !a; ++k)
    if (pbd::capsuleDistance(x[i], tools_to[k]) <= rest_r[i] + influence) a = 1;
  active[i] = a;
}

template <typename T>
__global__ void radiusKernel(int n, const Vec3<T>* x, const T* radii, T* radii_next, const T* rest_r,
                             const T* rest_cell, const std::int32_t* ov_off, const std::int32_t* ov_ids,
                             const Vec3<T>* samples, int sample_count, const std::uint8_t* active, T growth,
                             int bisection_steps) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const T r0 = rest_r[i];
  if (!active[i]) {
    radii_next[i] = r0;
    return;
  }
  const std::int32_t b = ov_off[i], e = ov_off[i + 1];
  radii_next[i] = pbd::radiusForCellVolume(x[i], r0, r0 * growth, rest_cell[i], x, radii, ov_ids + b, e - b, samples,
                                           sample_count, bisection_steps);
}

template <typename T>
__global__ void restRadiiKernel(int n, const int* live_n, T* radii, const T* rest_r) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= liveCount(live_n, n)) return;
  radii[i] = rest_r[i];
}

}  // namespace

template <typename T>
void PbdParticleKernels<T>::predict(unsigned blocks, cudaStream_t stream, int n, const int* live_n, Vec3<T>* x,
                                    Vec3<T>* v, Vec3<T>* x_prev, const T* w, Vec3<T> g, T damp, T dt,
                                    Vec3<T>* cheb_x1) {
  predictKernel<T><<<blocks, kThreads, 0, stream>>>(n, live_n, x, v, x_prev, w, g, damp, dt, cheb_x1);
  INC_CUDA_LAUNCH("pbd predict");
}

template <typename T>
void PbdParticleKernels<T>::kinematic(unsigned blocks, cudaStream_t stream, int k, Vec3<T>* x, const std::int32_t* ids,
                                      const Vec3<T>* from, const Vec3<T>* to, T t) {
  kinematicKernel<T><<<blocks, kThreads, 0, stream>>>(k, x, ids, from, to, t);
  INC_CUDA_LAUNCH("pbd kinematic");
}

template <typename T>
void PbdParticleKernels<T>::gatherKinematic(unsigned blocks, cudaStream_t stream, int k, const Vec3<T>* x,
                                            const std::int32_t* ids, Vec3<T>* from) {
  gatherKinematicKernel<T><<<blocks, kThreads, 0, stream>>>(k, x, ids, from);
  INC_CUDA_LAUNCH("pbd kinematic start positions");
}

template <typename T>
void PbdParticleKernels<T>::zeroKinematic(unsigned blocks, cudaStream_t stream, int k, T* w, const std::int32_t* ids) {
  zeroKinematicKernel<T><<<blocks, kThreads, 0, stream>>>(k, w, ids);
  INC_CUDA_LAUNCH("pbd kinematic w");
}

template <typename T>
void PbdParticleKernels<T>::velocity(unsigned blocks, cudaStream_t stream, int n, const int* live_n, const Vec3<T>* x,
                                     const Vec3<T>* x_prev, Vec3<T>* v, T inv_dt) {
  velocityKernel<T><<<blocks, kThreads, 0, stream>>>(n, live_n, x, x_prev, v, inv_dt);
  INC_CUDA_LAUNCH("pbd velocities");
}

template <typename T>
void PbdParticleKernels<T>::volumeActive(unsigned blocks, cudaStream_t stream, int n, const Vec3<T>* x, const T* rest_r,
                                         const pbd::CapsuleCollider<T>* tools_to, int nt, T influence,
                                         std::uint8_t* active) {
  volumeActiveKernel<T><<<blocks, kThreads, 0, stream>>>(n, x, rest_r, tools_to, nt, influence, active);
  INC_CUDA_LAUNCH("pbd volume active");
}

template <typename T>
void PbdParticleKernels<T>::radius(unsigned blocks, cudaStream_t stream, int n, const Vec3<T>* x, const T* radii,
                                   T* radii_next, const T* rest_r, const T* rest_cell, const std::int32_t* ov_off,
                                   const std::int32_t* ov_ids, const Vec3<T>* samples, int sample_count,
                                   const std::uint8_t* active, T growth, int bisection_steps) {
  radiusKernel<T><<<blocks, kThreads, 0, stream>>>(n, x, radii, radii_next, rest_r, rest_cell, ov_off, ov_ids, samples,
                                                   sample_count, active, growth, bisection_steps);
  INC_CUDA_LAUNCH("pbd radii");
}

template <typename T>
void PbdParticleKernels<T>::restRadii(unsigned blocks, cudaStream_t stream, int n, const int* live_n, T* radii,
                                      const T* rest_r) {
  restRadiiKernel<T><<<blocks, kThreads, 0, stream>>>(n, live_n, radii, rest_r);
  INC_CUDA_LAUNCH("pbd rest radii");
}

template struct PbdParticleKernels<float>;
template struct PbdParticleKernels<double>;

}  // namespace inc::cuda
