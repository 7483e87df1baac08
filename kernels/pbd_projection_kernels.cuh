// Host launch wrappers of the constraint-projection PBD kernels (kernels/pbd_projection_kernels.cu): a block's
// projection, the Jacobi gather, attachments, cluster rotations.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "physics/pbd_block.h"
#include "physics/vec3.h"

namespace inc::cuda {

// Each launches its kernel(s) on `stream` and checks the launch. The kernels live in one translation unit (no
// relocatable device code): other files launch them through these.
template <typename T>
struct PbdProjectionKernels {
  // Jacobi: every constraint of block b into its slots. `count` sizes the grid; in a patched model it is a bucket
  // (PbdCudaBackend::gridCount) and *live_count the constraint count, read on the device so that a captured frame
  // stays valid when a patch changes it (null: count itself).
  static void jacobi(cudaStream_t stream, const pbd::BlockView<T>& b, const pbd::SolveContext<T>& ctx, int count,
                     const int* live_count);
  // Gauss-Seidel: the constraints order[0 .. count) of one colour, in place.
  static void colour(cudaStream_t stream, const pbd::BlockView<T>& b, const pbd::SolveContext<T>& ctx,
                     const std::int32_t* order, int count);
  // Jacobi gather (`blocks` blocks of kThreads): each particle adds its slots' corrections.
  static void gather(unsigned blocks, cudaStream_t stream, int n, const int* live_n, const pbd::BlockView<T>& b,
                     Vec3<T>* x);
  // The k attachments (pbd::projectAttachment towards lerp(from, to, t)), `blocks` blocks of kThreads.
  static void attachments(unsigned blocks, cudaStream_t stream, int k, Vec3<T>* x, const T* w, const std::int32_t* ids,
                          const Vec3<T>* from, const Vec3<T>* to, const T* compliance, Vec3<T>* lambda, bool xpbd, T dt,
                          T t);
  // pbd::updateClusterRotation of every cluster of block b (not solved this frame), `blocks` blocks of kThreads.
  static void rotations(unsigned blocks, cudaStream_t stream, const pbd::BlockView<T>& b,
                        const pbd::SolveContext<T>& ctx, const int* live_count);
};

}  // namespace inc::cuda
