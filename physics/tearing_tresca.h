// Tresca tearing math (tresca paper eqs. 5-6): bond strains, per-particle extrema, yield tests, split side, seeded
// new-particle position, principal stresses.
#pragma once

#include <cmath>
#include <cstdint>

#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc::tear {

// ---------------------------------------------------------------------------------------------
// Bond strain rho = (|x_a - x_b| - d) / d (dimensionless engineering strain). The paper's rho is "the change
// in the distance of the particles"; we divide by the rest length d so that k is a modulus in Pa and
// k rho a stress, independent of the mesh resolution (docs/tearing.md).
template <typename T>
INC_HD T bondStrain(const Vec3<T>& xa, const Vec3<T>& xb, T rest) {
  if (!(rest > T(0))) return T(0);
  return (norm(xa - xb) - rest) / rest;
}

// Largest and smallest strain over one particle's bonds and the bonds (their other particles) that carry
// them. Ties keep the first in the particle's bond order (ascending partner index), so both backends agree.
template <typename T>
struct StrainExtrema {
  T rho_max = T(0), rho_min = T(0);
  std::int32_t partner_max = -1, partner_min = -1;  // other particle of the extreme bond
  int count = 0;                                    // bonds seen
};

template <typename T>
INC_HD void accumulateStrain(StrainExtrema<T>& e, T rho, std::int32_t partner) {
  if (e.count == 0 || rho > e.rho_max) {
    e.rho_max = rho;
    e.partner_max = partner;
  }
  if (e.count == 0 || rho < e.rho_min) {
    e.rho_min = rho;
    e.partner_min = partner;
  }
  ++e.count;
}

// Eq. 6: the largest and smallest bond stresses k rho stand in for the principal stresses sigma_1 and
// sigma_3 of eq. 5; the maximum shear stress is half their difference.
template <typename T>
INC_HD T trescaShear(T k, T rho_max, T rho_min) {
  return std::fabs(k * rho_max - k * rho_min) / T(2);
}

// Eq. 6 as a test: yield when |k rho_max - k rho_min| / 2 >= tau_f. A particle with fewer than two bonds
// has no stress difference and never yields. tau_f <= 0 would make every particle yield and is refused
// by the model validation, not here.
template <typename T>
INC_HD bool trescaYield(const StrainExtrema<T>& e, T k, T tau_f) {
  return e.count >= 2 && trescaShear(k, e.rho_max, e.rho_min) >= tau_f;
}

// The traditional criterion (Mueller et al. 2007): a bond breaks when its strain passes a threshold.
template <typename T>
INC_HD bool thresholdYield(const StrainExtrema<T>& e, T break_strain) {
  return e.count >= 1 && e.rho_max >= break_strain;
}

// ---------------------------------------------------------------------------------------------
// Counter-based random numbers: a hash of (seed, a, b, step) so that the random offset of a new particle
// depends only on the broken bond's particles and the step, not on thread order (CPU and GPU agree).
INC_HD std::uint32_t mix32(std::uint32_t h) {
  // lowbias32 finaliser (Wellons): full avalanche, cheap on both host and device.
  h ^= h >> 16;
  h *= 0x7feb352dU;
  h ^= h >> 15;
  h *= 0x846ca68bU;
  h ^= h >> 16;
  return h;
}

INC_HD std::uint32_t tearHash(std::uint32_t seed, std::uint32_t a, std::uint32_t b, std::uint32_t step) {
  std::uint32_t h = mix32(seed ^ 0x9e3779b9U);
  h = mix32(h ^ a);
  h = mix32(h ^ (b * 0x85ebca6bU));
  h = mix32(h ^ (step * 0xc2b2ae35U));
  return h;
}

// Uniform in [-1, 1) from the top 24 bits: bits * 2^-23 - 1 is exact in float and double, so both
// precisions and both backends draw the same value.
template <typename T>
INC_HD T tearUniform(std::uint32_t seed, std::uint32_t a, std::uint32_t b, std::uint32_t step) {
  const std::uint32_t bits = tearHash(seed, a, b, step) >> 8;  // [0, 2^24)
  return T(bits) * T(1.1920928955078125e-07) - T(1);
}

// ---------------------------------------------------------------------------------------------
// Where the new particle goes on the broken bond i -> j, as the fraction t of the way from i to j.
// The paper says the particle is created "at half the length" and that its position is proportional to
// the stress in the opposite direction; we read that as t = (sigma_max - sigma_min) / (2 sigma_max):
// 1/2 when the smallest stress is zero (the paper's half length), closer to i when the particle is
// stretched in every direction (sigma_min > 0), further when it is compressed across the bond. Then the
// paper's random perturbation: t (1 + range u), u in [-1, 1] (range = 0.1 is its 10 %), and the result is
// clamped into [t_lo, t_hi] so that the new particle is strictly between the two.
template <typename T>
INC_HD T predictedFraction(T sigma_max, T sigma_min) {
  if (!(sigma_max > T(0))) return T(0.5);
  return (sigma_max - sigma_min) / (T(2) * sigma_max);
}

template <typename T>
INC_HD T perturbedFraction(T t_pred, T range, T u, T t_lo, T t_hi) {
  T t = t_pred * (T(1) + range * u);
  if (t < t_lo) t = t_lo;
  if (t > t_hi) t = t_hi;
  return t;
}

// ---------------------------------------------------------------------------------------------
// Vertex split geometry. A yielding particle i is split by the plane through x_i perpendicular to the
// crack-opening direction (the broken bond, or the first principal direction); triangles whose centroid
// lies on the positive side go to the new particle.
template <typename T>
INC_HD bool onSplitSide(const Vec3<T>& centroid, const Vec3<T>& xi, const Vec3<T>& dir) {
  return dot(centroid - xi, dir) > T(0);
}

template <typename T>
INC_HD Vec3<T> triangleAreaVector(const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c) {
  return cross(b - a, c - a) * T(0.5);
}

// A triangle whose vertex moves from `old_v` to `new_v` (the other two fixed) stays valid when its area
// vector keeps its direction (no inversion) and keeps at least `min_ratio` of its area (no degeneracy).
template <typename T>
INC_HD bool moveKeepsTriangle(const Vec3<T>& old_v, const Vec3<T>& new_v, const Vec3<T>& b, const Vec3<T>& c,
                              T min_ratio) {
  const Vec3<T> a0 = triangleAreaVector(old_v, b, c), a1 = triangleAreaVector(new_v, b, c);
  const T n0 = norm2(a0);
  if (!(n0 > T(0))) return false;
  return dot(a0, a1) >= min_ratio * n0;  // projected area on the old normal >= min_ratio * old area
}

// ---------------------------------------------------------------------------------------------
// Principal-stress variant: the eigenvalues of a symmetric stress tensor in closed form (trigonometric
// solution of the characteristic cubic), sorted sigma_1 >= sigma_2 >= sigma_3.
template <typename T>
INC_HD void symmetricEigenvalues(const Mat3<T>& a, T& s1, T& s2, T& s3) {
  const T p1 = a(0, 1) * a(0, 1) + a(0, 2) * a(0, 2) + a(1, 2) * a(1, 2);
  const T q = trace(a) / T(3);
  const T d0 = a(0, 0) - q, d1 = a(1, 1) - q, d2 = a(2, 2) - q;
  const T p2 = d0 * d0 + d1 * d1 + d2 * d2 + T(2) * p1;
  const T p = std::sqrt(p2 / T(6));
  if (!(p > T(0))) {  // a multiple of the identity
    s1 = s2 = s3 = q;
    return;
  }
  Mat3<T> b = a;
  b(0, 0) -= q;
  b(1, 1) -= q;
  b(2, 2) -= q;
  b *= T(1) / p;
  T r = det(b) / T(2);
  if (r < T(-1)) r = T(-1);
  if (r > T(1)) r = T(1);
  const T phi = std::acos(r) / T(3);
  const T two_pi_3 = T(2.0943951023931957);
  s1 = q + T(2) * p * std::cos(phi);
  s3 = q + T(2) * p * std::cos(phi + two_pi_3);
  s2 = T(3) * q - s1 - s3;
}

// Unit eigenvector of a symmetric matrix for eigenvalue `lambda`: the largest cross product of two rows
// of (A - lambda I) (those rows span the orthogonal complement when lambda is simple). Returns the zero
// vector when lambda is (numerically) repeated, in which case no direction is preferred.
template <typename T>
INC_HD Vec3<T> symmetricEigenvector(const Mat3<T>& a, T lambda) {
  Mat3<T> m = a;
  m(0, 0) -= lambda;
  m(1, 1) -= lambda;
  m(2, 2) -= lambda;
  const Vec3<T> r0 = m.row(0), r1 = m.row(1), r2 = m.row(2);
  const Vec3<T> c01 = cross(r0, r1), c02 = cross(r0, r2), c12 = cross(r1, r2);
  const T n01 = norm2(c01), n02 = norm2(c02), n12 = norm2(c12);
  Vec3<T> best = c01;
  T nb = n01;
  if (n02 > nb) {
    best = c02;
    nb = n02;
  }
  if (n12 > nb) {
    best = c12;
    nb = n12;
  }
  const T scale = frobeniusNorm(a);
  const T tiny = (sizeof(T) == 4 ? T(1e-10) : T(1e-24)) * scale * scale * scale * scale;
  if (!(nb > tiny)) return Vec3<T>();
  return best * (T(1) / std::sqrt(nb));
}

// Bond stress tensor of one particle (virial form of its bonds): sigma = (1/n) sum_b k rho_b n_b n_b^T with
// n_b the unit bond direction. For a membrane it is plane stress: one eigenvalue (normal to the sheet) is 0,
// which Tresca must include (max shear = max(|s1 - s2|, |s1|, |s2|) / 2 in the plane's terms).
template <typename T>
INC_HD void accumulateBondStress(Mat3<T>& sigma, const Vec3<T>& xi, const Vec3<T>& xj, T rest, T k) {
  const Vec3<T> d = xj - xi;
  const T len = norm(d);
  if (!(len > T(0)) || !(rest > T(0))) return;
  const Vec3<T> n = d * (T(1) / len);
  sigma += outer(n, n) * (k * (len - rest) / rest);
}

// Eq. 5's shear from the largest and smallest principal stresses: tau = (sigma_1 - sigma_3) / 2. detectYield
// calls it with the eigenvalues it already has (it needs them for the split direction too).
template <typename T>
INC_HD T trescaShearOfPrincipals(T sigma_1, T sigma_3) {
  return (sigma_1 - sigma_3) / T(2);
}

// Eq. 5 with the real principal stresses of sigma: tau = (sigma_1 - sigma_3) / 2 >= tau_f.
template <typename T>
INC_HD T trescaShearPrincipal(const Mat3<T>& sigma) {
  T s1, s2, s3;
  symmetricEigenvalues(sigma, s1, s2, s3);
  return trescaShearOfPrincipals(s1, s3);
}

}  // namespace inc::tear
