// Leapfrog (eq. 10) in kick-drift-kick form with damping, Dirichlet and prescribed particles; stable step.
#pragma once

#include <cstdint>

#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc {

// How a particle moves: by Newton (eq. 10), held where it is, or driven to a target (tools).
enum MlsParticleKind : std::uint8_t { kMlsFree = 0, kMlsFixed = 1, kMlsPrescribed = 2 };

// Half kick of velocity Verlet (leapfrog with synchronised velocities): v <- v + h (f/m + g), with the
// mass-proportional damping force -c m v taken implicitly, (v + h a) / (1 + c h), so that it can only
// remove energy and never limits the step. h = dt/2 (s), f (N), g (m/s^2), c (1/s).
template <typename T>
INC_HD Vec3<T> mlsHalfKick(const Vec3<T>& v, const Vec3<T>& f, T mass, const Vec3<T>& g, T h, T damping) {
  const Vec3<T> a = f * (T(1) / mass) + g;
  return (v + a * h) * (T(1) / (T(1) + damping * h));
}

// A prescribed particle moves on a straight line to its target, reaching it after `remaining` substeps.
template <typename T>
INC_HD void mlsPrescribedStep(Vec3<T>& u, Vec3<T>& v, const Vec3<T>& target, T dt, int remaining) {
  const Vec3<T> du = (target - u) * (T(1) / T(remaining > 0 ? remaining : 1));
  v = du * (T(1) / dt);
  u += du;
}

// Courant number of the explicit step: dt_max = kMlsCourant * spacing / c_p. Calibrated against the largest
// eigenfrequency of the discrete MLS operator (power iteration in tests/sim/test_mls_validation.cpp,
// StableStepIsBelowTheDiscreteLimit): with support 2 spacings, jittered lattices and the volume penalty the
// true limit 2 / omega_max is 0.80 .. 1.05 spacing / c_p for nu in [0, 0.499]; 0.7 keeps a margin. The
// scene's safety factor (default 0.5) multiplies this. It is the rest-state (linearised) limit: a strongly
// stretched SVK material stiffens, which the runner's guard catches (finite == false, smaller step).
constexpr double kMlsCourant = 0.7;

// Linearised P-wave modulus M = lambda + 2 mu + k_v (Pa; lambda and k_v as in MlsCoefficients, so M is
// the material's lambda + 2 mu, plus any bulk stiffening of a penalty above K) and the largest stable
// step (s) for particle spacing (m) and rest density (kg/m^3), safety factor 1.
template <typename T>
INC_HD T mlsStableTimeStep(T mu, T lambda, T k_volume, T density, T spacing) {
  const T modulus = lambda + T(2) * mu + k_volume;
  const T cp = std::sqrt(modulus / density);
  return T(kMlsCourant) * spacing / cp;
}

}  // namespace inc
