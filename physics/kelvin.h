// Kelvin fundamental solutions of 3D linear elastostatics (displacement U* and traction T*), per point pair.
#pragma once

#include "physics/vec3.h"

namespace inc {

// U*_kl(x, xi): displacement at x in direction l due to a unit point force at xi in direction k
// (metres per newton): 1 / (16 pi mu (1 - nu) r) [(3 - 4 nu) delta_kl + r_,k r_,l], r = x - xi.
template <typename T>
INC_HD Mat3<T> kelvinDisplacement(const Vec3<T>& r_vec, T shear_pa, T nu) {
  const T r = norm(r_vec);
  const Vec3<T> d = r_vec * (T(1) / r);
  const T c = T(1) / (T(16) * T(M_PI) * shear_pa * (T(1) - nu) * r);
  Mat3<T> u;
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) u(k, l) = c * ((k == l ? T(3) - T(4) * nu : T(0)) + d[k] * d[l]);
  return u;
}

// T*_kl(x, xi): traction at x (outward unit normal n at x) in direction l due to a unit point force
// at xi in direction k (1 / m^2): -1 / (8 pi (1 - nu) r^2) { dr/dn [(1 - 2 nu) delta_kl + 3 r_,k r_,l]
// - (1 - 2 nu) (r_,k n_l - r_,l n_k) }.
template <typename T>
INC_HD Mat3<T> kelvinTraction(const Vec3<T>& r_vec, const Vec3<T>& n, T nu) {
  const T r = norm(r_vec);
  const Vec3<T> d = r_vec * (T(1) / r);
  const T drdn = dot(d, n);
  const T c = T(-1) / (T(8) * T(M_PI) * (T(1) - nu) * r * r);
  const T a = T(1) - T(2) * nu;
  Mat3<T> p;
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l)
      p(k, l) = c * (drdn * ((k == l ? a : T(0)) + T(3) * d[k] * d[l]) - a * (d[k] * n[l] - d[l] * n[k]));
  return p;
}

}  // namespace inc
