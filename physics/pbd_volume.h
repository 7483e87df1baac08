// Local volume preservation by radius adjustment: power-cell volume of a sphere within the union, and the radius that
// restores it.
#pragma once

#include <cmath>
#include <cstdint>

#include "physics/distance.h"
#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc::pbd {

// The union U of balls B_i = B(c_i, r_i) splits exactly into the pieces B_i n P_i, where P_i is sphere i's
// power (Laguerre) cell {x : |x - c_i|^2 - r_i^2 <= |x - c_j|^2 - r_j^2 for all j}. A point of B_i can only be
// claimed by a ball that contains it, so only overlapping spheres matter. V_i = vol(B_i n P_i) is the part of
// the organ's volume that sphere i owns; sum_i V_i = vol(U). See docs/pbd.md.
//
// Sample k of `count` fixed, well-spread points in the unit ball (radius stratified by volume, direction on a
// Fibonacci spiral; a coprime permutation decorrelates the two). Computed once on the host and uploaded, so
// both backends test the same points.
template <typename T>
INC_HD Vec3<T> unitBallSample(int k, int count) {
  const T golden_angle = T(2.399963229728653);
  const T z = T(1) - T(2) * (T(k) + T(0.5)) / T(count);
  const T rho_xy = std::sqrt(T(1) - z * z > T(0) ? T(1) - z * z : T(0));
  const T phi = golden_angle * T(k);
  const int kr = int((std::int64_t(k) * 37 + 11) % count);
  const T radius = std::cbrt((T(kr) + T(0.5)) / T(count));
  return Vec3<T>(rho_xy * std::cos(phi), rho_xy * std::sin(phi), z) * radius;
}

// Sampled V_i for sphere i with radius r (its neighbours keep theirs). nbrs: the spheres that may overlap i.
template <typename T>
INC_HD T powerCellVolume(const Vec3<T>& ci, T r, const Vec3<T>* centers, const T* radii, const std::int32_t* nbrs,
                         int nbr_count, const Vec3<T>* samples, int sample_count) {
  int inside = 0;
  for (int k = 0; k < sample_count; ++k) {
    const Vec3<T> x = ci + samples[k] * r;
    const T power_i = distance2Exact(x, ci) - r * r;
    bool own = true;
    for (int n = 0; n < nbr_count && own; ++n) {
      const std::int32_t j = nbrs[n];
      if (distance2Exact(x, centers[j]) - radii[j] * radii[j] < power_i) own = false;
    }
    inside += own ? 1 : 0;
  }
  const T ball = T(4.188790204786391) * r * r * r;  // 4/3 pi r^3
  return ball * T(inside) / T(sample_count);
}

// Radius in [r_min, r_max] at which the sampled V_i reaches `target` (bisection: V_i grows with r_i, since
// both the ball and its power cell grow). Returns r_max when even that does not reach the target (the
// growth limit caps the effect of a pathological squeeze) and r_min when V_i(r_min) already does.
template <typename T>
INC_HD T radiusForCellVolume(const Vec3<T>& ci, T r_min, T r_max, T target, const Vec3<T>* centers, const T* radii,
                             const std::int32_t* nbrs, int nbr_count, const Vec3<T>* samples, int sample_count,
                             int bisection_steps) {
  if (powerCellVolume(ci, r_min, centers, radii, nbrs, nbr_count, samples, sample_count) >= target) return r_min;
  if (powerCellVolume(ci, r_max, centers, radii, nbrs, nbr_count, samples, sample_count) < target) return r_max;
  T lo = r_min, hi = r_max;
  for (int s = 0; s < bisection_steps; ++s) {
    const T mid = T(0.5) * (lo + hi);
    if (powerCellVolume(ci, mid, centers, radii, nbrs, nbr_count, samples, sample_count) >= target)
      hi = mid;
    else
      lo = mid;
  }
  return hi;
}

}  // namespace inc::pbd
