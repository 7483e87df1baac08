// Host launch wrappers of the contact PBD kernels (kernels/pbd_contact_kernels.cu): a particle's end of an iteration,
// alone or fused with the last Jacobi gather.
#pragma once

#include <cuda_runtime.h>

#include "kernels/pbd_chebyshev_args.cuh"
#include "physics/pbd_block.h"
#include "physics/pbd_collision.h"
#include "physics/vec3.h"

namespace inc::cuda {

// What a particle's contacts read besides its position: its radius and contact inset (null: none), its position at
// the substep's start and inverse mass, the colliders (tools move from tools_from to tools_to over the frame).
template <typename T>
struct PbdContactScene {
  const T* r = nullptr;
  const T* inset = nullptr;
  const Vec3<T>* x_prev = nullptr;
  const T* w = nullptr;
  const pbd::PlaneCollider<T>* planes = nullptr;
  int np = 0;
  const pbd::BoxCollider<T>* boxes = nullptr;
  int nb = 0;
  const pbd::CapsuleCollider<T>* tools_from = nullptr;
  const pbd::CapsuleCollider<T>* tools_to = nullptr;
  int nt = 0;
};

// Each launches its kernel with `blocks` blocks of kThreads on `stream` and checks the launch. Both take the
// iteration's Chebyshev step (ch; mode Off: none) over the particles and every multiplier. The kernels live in one
// translation unit (no relocatable device code): other files launch them through these.
template <typename T>
struct PbdContactKernels {
  // The iteration's end (pbd::endIteration) of particles [0, live count), tools at times t0 .. t of the frame.
  static void contacts(unsigned blocks, cudaStream_t stream, int n, const int* live_n, Vec3<T>* x,
                       const PbdContactScene<T>& scene, T t0, T t, const ChebyshevArgs<T>& ch);
  // Block b's Jacobi gather, then the iteration's end, per particle in one pass.
  static void gatherContacts(unsigned blocks, cudaStream_t stream, int n, const int* live_n, const pbd::BlockView<T>& b,
                             Vec3<T>* x, const PbdContactScene<T>& scene, T t0, T t, const ChebyshevArgs<T>& ch);
};

}  // namespace inc::cuda
