// Boussinesq-Cerruti solutions: the elastic half-space under a point force on its surface (displacement, stress).
#pragma once

#include "physics/vec3.h"

namespace inc {

// Frame: the surface is z = 0 with the outward normal +z, the solid is z <= 0; the unit force acts at the
// origin. Returns B with B(k, l) = u_l(x) for a unit force in direction k (metres per newton), the same
// convention as kelvinDisplacement. Normal force: Boussinesq; tangential: Cerruti (K. L. Johnson, Contact
// Mechanics, 1985, chapter 3, written there with z into the solid; we evaluate them at zj = -z and flip the
// z components; tests/physics/test_haptic_boussinesq.cpp checks equilibrium, the free surface and reciprocity).
// Singular at the origin and on the normal line above it (x = y = 0, z > 0, outside the solid): guard_rel > 0
// bounds rho + zj below by guard_rel * rho there (only points of a concave organ above its tangent plane come
// near that line; inside the solid rho + zj >= rho, so it never acts).
template <typename T>
INC_HD Mat3<T> boussinesqCerrutiDisplacement(const Vec3<T>& x, T shear_pa, T nu, T guard_rel = T(0)) {
  const T xx = x.x, yy = x.y, zj = -x.z;  // zj: depth below the surface
  const T rho = norm(x);
  T rz = rho + zj;
  if (rz < guard_rel * rho) rz = guard_rel * rho;
  const T a = T(1) - T(2) * nu;
  const T c = T(1) / (T(4) * T(M_PI) * shear_pa);
  const T r3 = rho * rho * rho;
  Mat3<T> bj;  // Johnson frame (zj into the solid): row = force direction, column = displacement component
  // Normal force along +zj (pushing into the solid).
  bj(2, 0) = c * (xx * zj / r3 - a * xx / (rho * rz));
  bj(2, 1) = c * (yy * zj / r3 - a * yy / (rho * rz));
  bj(2, 2) = c * (zj * zj / r3 + T(2) * (T(1) - nu) / rho);
  // Tangential force along +x, and along +y (the same with x and y exchanged).
  bj(0, 0) = c * (T(1) / rho + xx * xx / r3 + a * (T(1) / rz - xx * xx / (rho * rz * rz)));
  bj(0, 1) = c * (xx * yy / r3 - a * xx * yy / (rho * rz * rz));
  bj(0, 2) = c * (xx * zj / r3 + a * xx / (rho * rz));
  bj(1, 1) = c * (T(1) / rho + yy * yy / r3 + a * (T(1) / rz - yy * yy / (rho * rz * rz)));
  bj(1, 0) = bj(0, 1);
  bj(1, 2) = c * (yy * zj / r3 + a * yy / (rho * rz));
  // Back to z outward: a force along +z is a force along -zj, and u_z = -u_zj.
  Mat3<T> b;
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) b(k, l) = ((k == 2) != (l == 2) ? T(-1) : T(1)) * bj(k, l);
  return b;
}

// Stresses (Pa per newton) at x for unit forces along x, y and z (out[k]): Hooke's law on the displacement
// gradient taken by central differences with step h_rel * |x| (relative error ~ h_rel^2; 1e-4 gives ~1e-8).
template <typename T>
INC_HD void boussinesqCerrutiStresses(const Vec3<T>& x, T shear_pa, T nu, Mat3<T> out[3], T h_rel = T(1e-4),
                                      T guard_rel = T(0)) {
  const T h = h_rel * norm(x);
  T grad[3][3][3];  // grad[k][m][l] = d u_l / d x_m for the force along k
  for (int m = 0; m < 3; ++m) {
    Vec3<T> xp = x, xm = x;
    xp[m] += h;
    xm[m] -= h;
    const Mat3<T> up = boussinesqCerrutiDisplacement(xp, shear_pa, nu, guard_rel);
    const Mat3<T> um = boussinesqCerrutiDisplacement(xm, shear_pa, nu, guard_rel);
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) grad[k][m][l] = (up(k, l) - um(k, l)) / (T(2) * h);
  }
  const T lambda = T(2) * shear_pa * nu / (T(1) - T(2) * nu);
  for (int k = 0; k < 3; ++k) {
    const T div = grad[k][0][0] + grad[k][1][1] + grad[k][2][2];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        out[k](i, j) = shear_pa * (grad[k][i][j] + grad[k][j][i]) + (i == j ? lambda * div : T(0));
  }
}

// The stress for one force direction k (see boussinesqCerrutiStresses).
template <typename T>
INC_HD Mat3<T> boussinesqCerrutiStress(const Vec3<T>& x, int k, T shear_pa, T nu, T h_rel = T(1e-4),
                                       T guard_rel = T(0)) {
  Mat3<T> s[3];
  boussinesqCerrutiStresses(x, shear_pa, nu, s, h_rel, guard_rel);
  return s[k];
}

}  // namespace inc
