// Chebyshev semi-iterative acceleration of the Jacobi PBD iterations: the weights and the per-value blend.
#pragma once

#include <cstdint>

#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc::pbd {

// Wang, "A Chebyshev semi-iterative approach for accelerating projective and position-based dynamics"
// (ACM TOG 34(6), 2015): after Jacobi iteration k has produced q^ from q^(k-1), the iterate becomes
//   q^(k) = w_k (q^ - q^(k-2)) + q^(k-2),   w_1 = 1,  w_2 = 2 / (2 - rho^2),  w_k = 4 / (4 - rho^2 w_(k-1)),
// rho being an estimate of the Jacobi iteration's spectral radius. We blend the XPBD multipliers with the same
// weights as the positions: a multiplier is the constraint force the positions carry, and blending the positions
// alone leaves the two inconsistent (measured: the converged sag then depends on rho). A fixed point of the plain
// iteration is a fixed point of the blended one, so the equilibrium is the same; only the way there is shorter.
//
// The last iteration of a substep is never blended: its result becomes the substep's velocity, and an
// extrapolated last iterate injects energy every substep (measured on the liver-sized block with a first version
// that blended it: NaN within 90 frames at 2 iterations, rho 0.85).

// What one iteration does with the Chebyshev state.
enum class ChebyshevMode : std::int32_t {
  Off = 0,    // acceleration off, or the substep's last iteration: nothing read or written
  Shift = 1,  // first iteration (w = 1): record the iterates only
  Blend = 2,  // blend with the iterate two back, then record
};

// The largest rho accepted (validateFrameInput), with a margin: 0.98 diverged on the liver-sized block (bench_pbd)
// at 5 iterations, 0.99 failed the energy bound of tests/physics/test_pbd_chebyshev.cpp; 0.95 and below passed both.
constexpr double kChebyshevMaxRho = 0.9;

// Weight and mode of iteration `it` (0-based) of `iterations`; `weight` carries w_(k-1) in and w_k out, so a
// caller walks the iterations in order starting from weight = 1.
template <typename T>
INC_HD ChebyshevMode chebyshevIteration(int it, int iterations, T rho, T& weight) {
  if (!(rho > T(0)) || it + 1 >= iterations) return ChebyshevMode::Off;
  if (it == 0) {
    weight = T(1);
    return ChebyshevMode::Shift;
  }
  const T r2 = rho * rho;
  weight = it == 1 ? T(2) / (T(2) - r2) : T(4) / (T(4) - r2 * weight);
  return ChebyshevMode::Blend;
}

// The blend itself: `hat` (this iteration's plain Jacobi result) extrapolated from the iterate two back.
template <typename T>
INC_HD Vec3<T> chebyshevBlend(const Vec3<T>& hat, const Vec3<T>& two_back, T weight) {
  return (hat - two_back) * weight + two_back;
}

// A position's step before its contacts: blended when asked (movable particles only), and the one-back iterate
// moved into the two-back slot. chebyshevRecord records the new one-back iterate once the position is final.
template <typename T>
INC_HD Vec3<T> chebyshevStep(const Vec3<T>& hat, const Vec3<T>& one_back, Vec3<T>& two_back, T weight,
                             ChebyshevMode mode, bool movable) {
  Vec3<T> out = hat;
  if (mode == ChebyshevMode::Blend && movable) out = chebyshevBlend(hat, two_back, weight);
  if (mode != ChebyshevMode::Off) two_back = one_back;
  return out;
}

template <typename T>
INC_HD bool sameVec(const Vec3<T>& a, const Vec3<T>& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}

// Records a position's final value. A particle that a contact moved restarts: its two-back iterate becomes the
// contact's result, so the next iteration extrapolates only its own step, not the contact's push. A contact is an
// inequality whose correction is not a step of the linear iteration the weights assume; extrapolating it (from the
// predicted position below a floor, say) throws the particle off the surface (measured: kinetic energy above the
// block's starting potential energy in a 0.1 s substep, rho 0.85-0.95).
template <typename T>
INC_HD void chebyshevRecord(const Vec3<T>& value, Vec3<T>& one_back, Vec3<T>& two_back, ChebyshevMode mode,
                            bool contact) {
  if (mode == ChebyshevMode::Off) return;
  one_back = value;
  if (contact) two_back = value;
}

// A particle's end of a Jacobi iteration, the same on both backends: its Chebyshev step (none when `mode` is Off;
// the iterates may then be null), then `contacts` (movable particles only), then the record (a contact restarts).
template <typename T, class Contacts>
INC_HD Vec3<T> endIteration(Vec3<T> x, bool movable, Vec3<T>* one_back, Vec3<T>* two_back, T weight, ChebyshevMode mode,
                            const Contacts& contacts) {
  if (mode != ChebyshevMode::Off) x = chebyshevStep(x, *one_back, *two_back, weight, mode, movable);
  const Vec3<T> free = x;
  if (movable) x = contacts(x);
  if (mode != ChebyshevMode::Off) chebyshevRecord(x, *one_back, *two_back, mode, !sameVec(x, free));
  return x;
}

// A multiplier's whole step (blend, shift, record). Every multiplier starts a substep at zero, so the first
// iteration's two-back value is zero and no one-back array needs clearing at the substep's start.
template <typename T>
INC_HD void chebyshevMultiplier(Vec3<T>& lambda, Vec3<T>& one_back, Vec3<T>& two_back, T weight, ChebyshevMode mode) {
  if (mode == ChebyshevMode::Off) return;
  if (mode == ChebyshevMode::Blend) lambda = chebyshevBlend(lambda, two_back, weight);
  two_back = mode == ChebyshevMode::Shift ? Vec3<T>() : one_back;
  one_back = lambda;
}

}  // namespace inc::pbd
