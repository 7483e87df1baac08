// Contact PBD kernels of the per-block frame and their host launch wrappers: a particle's end of an iteration
// (colliders, Chebyshev step), alone or after the last Jacobi gather.
#include "kernels/pbd_contact_kernels.cuh"

#include "kernels/cuda_check.h"
#include "kernels/pbd_chebyshev_args.cuh"
#include "kernels/pbd_launch.cuh"
#include "kernels/pbd_particle_ops.cuh"
#include "physics/pbd_block.h"

namespace inc::cuda {

namespace {

template <typename T>
__global__ void contactKernel(int n, const int* live_n, Vec3<T>* x, const T* r, const T* inset, const Vec3<T>* x_prev,
                              const T* w, const pbd::PlaneCollider<T>* planes, int np, const pbd::BoxCollider<T>* boxes,
                              int nb, const pbd::CapsuleCollider<T>* tools_from,
                              const pbd::CapsuleCollider<T>* tools_to, int nt, T t0, T t, ChebyshevArgs<T> ch) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < liveCount(live_n, n))
    x[i] = endIterationAt(i, x[i], r, inset, x_prev, w, planes, np, boxes, nb, tools_from, tools_to, nt, t0, t, ch);
  chebyshevMultipliers(ch);
}

// The last Jacobi block's gather and then the iteration's contacts, per particle in one pass: a particle's contact
// reads only its own gathered position, so this is the two kernels' result (the same operations on each particle
// in the same order) without the second pass over the positions and its launch. Both contact kernels take the
// iteration's Chebyshev step (positions before their contacts, as the CPU's contact phase does, and every multiplier).
template <typename T>
__global__ void gatherContactKernel(int n, const int* live_n, pbd::BlockView<T> b, Vec3<T>* x, const T* r,
                                    const T* inset, const Vec3<T>* x_prev, const T* w,
                                    const pbd::PlaneCollider<T>* planes, int np, const pbd::BoxCollider<T>* boxes,
                                    int nb, const pbd::CapsuleCollider<T>* tools_from,
                                    const pbd::CapsuleCollider<T>* tools_to, int nt, T t0, T t, ChebyshevArgs<T> ch) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < liveCount(live_n, n))
    x[i] = endIterationAt(i, x[i] + gatherSum(b, i), r, inset, x_prev, w, planes, np, boxes, nb, tools_from, tools_to,
                          nt, t0, t, ch);
  chebyshevMultipliers(ch);
}

}  // namespace

template <typename T>
void PbdContactKernels<T>::contacts(unsigned blocks, cudaStream_t stream, int n, const int* live_n, Vec3<T>* x,
                                    const PbdContactScene<T>& s, T t0, T t, const ChebyshevArgs<T>& ch) {
  contactKernel<T><<<blocks, kThreads, 0, stream>>>(n, live_n, x, s.r, s.inset, s.x_prev, s.w, s.planes, s.np, s.boxes,
                                                    s.nb, s.tools_from, s.tools_to, s.nt, t0, t, ch);
  INC_CUDA_LAUNCH("pbd contacts");
}

template <typename T>
void PbdContactKernels<T>::gatherContacts(unsigned blocks, cudaStream_t stream, int n, const int* live_n,
                                          const pbd::BlockView<T>& b, Vec3<T>* x, const PbdContactScene<T>& s, T t0,
                                          T t, const ChebyshevArgs<T>& ch) {
  gatherContactKernel<T><<<blocks, kThreads, 0, stream>>>(n, live_n, b, x, s.r, s.inset, s.x_prev, s.w, s.planes, s.np,
                                                          s.boxes, s.nb, s.tools_from, s.tools_to, s.nt, t0, t, ch);
  INC_CUDA_LAUNCH("pbd gather + contacts");
}

template struct PbdContactKernels<float>;
template struct PbdContactKernels<double>;

}  // namespace inc::cuda
