// Device views of the Chebyshev-accelerated Jacobi iterates (positions and every multiplier list) and the per-iteration
// multiplier step.
#pragma once

#include "physics/pbd_chebyshev.h"
#include "physics/vec3.h"

namespace inc::cuda {

// The solved blocks' multipliers and the attachments' (PbdCudaBackend refuses a model with more blocks).
constexpr int kMaxChebyshevLists = 9;

template <typename T>
struct ChebyshevArgs {
  pbd::ChebyshevMode mode = pbd::ChebyshevMode::Off;
  T weight = T(1);
  Vec3<T>* x1 = nullptr;  // positions one iteration back
  Vec3<T>* x2 = nullptr;  // two back
  int lists = 0;
  int total = 0;  // multipliers over all lists
  Vec3<T>* lambda[kMaxChebyshevLists] = {};
  Vec3<T>* l1[kMaxChebyshevLists] = {};
  Vec3<T>* l2[kMaxChebyshevLists] = {};
  int end[kMaxChebyshevLists] = {};  // cumulative counts: list l holds [end[l-1], end[l]) of the flat index
};

// Every multiplier's step, the launch's threads striding over the flat index (the iteration's projections are
// ordered before the launch on the stream; each multiplier is touched by one thread).
template <typename T>
__device__ __forceinline__ void chebyshevMultipliers(const ChebyshevArgs<T>& a) {
  if (a.mode == pbd::ChebyshevMode::Off) return;
  for (int j = blockIdx.x * blockDim.x + threadIdx.x; j < a.total; j += gridDim.x * blockDim.x) {
    int l = 0;
    while (j >= a.end[l]) ++l;
    const int k = j - (l > 0 ? a.end[l - 1] : 0);
    pbd::chebyshevMultiplier(a.lambda[l][k], a.l1[l][k], a.l2[l][k], a.weight, a.mode);
  }
}

}  // namespace inc::cuda
