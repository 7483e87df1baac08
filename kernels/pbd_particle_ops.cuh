// Per-particle device steps shared by the per-block PBD kernels and the grid frame: the Jacobi gather and a particle's
// end of an iteration.
#pragma once

#include <cstdint>

#include "kernels/pbd_chebyshev_args.cuh"
#include "physics/pbd_block.h"
#include "physics/pbd_chebyshev.h"
#include "physics/pbd_collision.h"
#include "physics/vec3.h"

namespace inc::cuda {

// Jacobi gather: each particle sums its own slots' corrections (no atomics, fixed order): pbd::gatherCorrection's
// sum in its order, with the loads of four slots issued before their additions (the slots are scattered lines
// in L2; one at a time, each addition waited for two dependent loads).
template <typename T>
__device__ __forceinline__ Vec3<T> gatherSum(const pbd::BlockView<T>& b, int i) {
  const std::int32_t k1 = b.particle_offsets[i + 1];
  std::int32_t k = b.particle_offsets[i];
  Vec3<T> sum;
  for (; k + 4 <= k1; k += 4) {
    const std::int32_t s0 = b.particle_slots[k], s1 = b.particle_slots[k + 1], s2 = b.particle_slots[k + 2],
                       s3 = b.particle_slots[k + 3];
    const Vec3<T> d0 = b.slot_corr[s0], d1 = b.slot_corr[s1], d2 = b.slot_corr[s2], d3 = b.slot_corr[s3];
    sum += d0;
    sum += d1;
    sum += d2;
    sum += d3;
  }
  for (; k < k1; ++k) sum += b.slot_corr[b.particle_slots[k]];
  return sum;
}

// A particle's end of an iteration (pbd::endIteration): the Chebyshev step, the contacts, the record.
template <typename T>
__device__ __forceinline__ Vec3<T> endIterationAt(int i, Vec3<T> xi, const T* r, const T* inset, const Vec3<T>* x_prev,
                                                  const T* w, const pbd::PlaneCollider<T>* planes, int np,
                                                  const pbd::BoxCollider<T>* boxes, int nb,
                                                  const pbd::CapsuleCollider<T>* tools_from,
                                                  const pbd::CapsuleCollider<T>* tools_to, int nt, T t0, T t,
                                                  const ChebyshevArgs<T>& ch) {
  const bool on = ch.mode != pbd::ChebyshevMode::Off;
  return pbd::endIteration(xi, w[i] > T(0), on ? ch.x1 + i : nullptr, on ? ch.x2 + i : nullptr, ch.weight, ch.mode,
                           [&](const Vec3<T>& p) {
                             return pbd::resolveContacts(p, r[i], inset ? inset[i] : T(0), x_prev + i, planes, np,
                                                         boxes, nb, tools_from, tools_to, nt, t0, t);
                           });
}

}  // namespace inc::cuda
