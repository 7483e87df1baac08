// St. Venant-Kirchhoff continuum math of the MLS solid: gradient (eq. 5), Green strain (eq. 7), stress,
// energy density (eq. 8), first Piola-Kirchhoff stress and the volume-preserving penalty.
#pragma once

#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc {

// Material coefficients in the solver's precision (Pa, 1/s). The energy density is
//   psi = mu E:E + lambda/2 tr(E)^2 + k_volume/2 (J - 1)^2,
// where `lambda` is the Lame parameter less the part of the bulk response that the volume term carries
// (see mlsSplitCoefficients): both (J - 1) and tr(E) equal tr(grad u) to first order, so the split keeps
// the small-strain material exactly the requested (E, nu) while J = det F resists collapse and inversion.
template <typename T>
struct MlsCoefficients {
  T mu = T(0);        // Lame shear modulus
  T lambda = T(0);    // coefficient of tr(E) in S (Lame lambda minus the moved bulk part; may be < 0)
  T k_volume = T(0);  // volume penalty modulus (0: off)
  T damping = T(0);   // mass-proportional damping, 1/s
};

// Lame parameters from Young's modulus (Pa) and Poisson ratio (-1 < nu < 0.5).
template <typename T>
INC_HD void lameParameters(T youngs, T poisson, T& mu, T& lambda) {
  mu = youngs / (T(2) * (T(1) + poisson));
  lambda = youngs * poisson / ((T(1) + poisson) * (T(1) - T(2) * poisson));
}

// Coefficients from Young's modulus (Pa), Poisson ratio and the volume penalty k_v = zeta K (K the bulk
// modulus, zeta = volume_stiffness >= 0): the penalty takes over min(k_v, K) of the bulk response from the
// tr(E)^2 term. For zeta <= 1 the linearised material is unchanged (psi = mu |dev E|^2 + (1 - zeta) K/2
// tr(E)^2 + zeta K/2 (J - 1)^2 >= 0); zeta > 1 stiffens the linear bulk modulus to zeta K on purpose.
template <typename T>
INC_HD MlsCoefficients<T> mlsSplitCoefficients(T youngs, T poisson, bool volume_preservation, T zeta, T damping) {
  MlsCoefficients<T> c;
  T lame = T(0);
  lameParameters(youngs, poisson, c.mu, lame);
  const T bulk = lame + T(2) * c.mu / T(3);
  c.k_volume = volume_preservation ? zeta * bulk : T(0);
  c.lambda = lame - (c.k_volume < bulk ? c.k_volume : bulk);
  c.damping = damping;
  return c;
}

// eq. 5 accumulation, in the F = I + G convention (G_ab = du_a / dX_b):
// B += w_ij (u_j - u_i) x_ij^T with x_ij = X_j - X_i; then G_i = B A_i^{-1}. The paper's x_ij = x_i - x_j
// paired with (u_j - u_i) flips the sign of G; this form reproduces a linear field exactly.
template <typename T>
INC_HD void accumulateGradient(Mat3<T>& b, const Vec3<T>& du, const Vec3<T>& xij, T w) {
  const Vec3<T> wdu = du * w;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) b.m[r][c] += wdu[r] * xij[c];
}

// Green-Saint-Venant strain E = 1/2 (F^T F - I) = 1/2 (G + G^T + G^T G), evaluated from G so that small
// strains keep their relative accuracy in float32. The paper's eq. 7 tensor is epsilon = 2 E.
template <typename T>
INC_HD Mat3<T> greenStrain(const Mat3<T>& g) {
  const Mat3<T> gtg = transpose(g) * g;
  Mat3<T> e;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) e.m[r][c] = T(0.5) * (g.m[r][c] + g.m[c][r] + gtg.m[r][c]);
  return e;
}

// Isotropic St. Venant-Kirchhoff second Piola-Kirchhoff stress S = lambda tr(E) I + 2 mu E (Pa).
template <typename T>
INC_HD Mat3<T> svkStress(const Mat3<T>& e, T mu, T lambda) {
  Mat3<T> s = e * (T(2) * mu);
  const T lt = lambda * trace(e);
  s.m[0][0] += lt;
  s.m[1][1] += lt;
  s.m[2][2] += lt;
  return s;
}

// eq. 8 energy density psi = mu E:E + lambda/2 tr(E)^2 = 1/2 E:S (J/m^3).
template <typename T>
INC_HD T svkEnergyDensity(const Mat3<T>& e, T mu, T lambda) {
  const T tr = trace(e);
  return mu * ddot(e, e) + T(0.5) * lambda * tr * tr;
}

// det(I + G) - 1 from the invariants of G (tr G + I2(G) + det G): no cancellation for small G.
template <typename T>
INC_HD T volumeChange(const Mat3<T>& g) {
  const T tr = trace(g);
  const T tr_g2 = ddot(g, transpose(g));  // tr(G G)
  return tr + T(0.5) * (tr * tr - tr_g2) + det(g);
}

// Cofactor matrix cof(F) = dJ/dF = J F^{-T} (defined for singular and inverted F as well).
template <typename T>
INC_HD Mat3<T> cofactor(const Mat3<T>& f) {
  return transpose(adjugate(f));
}

// Everything pass 1 derives at one particle from its gradient G.
template <typename T>
struct MlsStressPoint {
  Mat3<T> piola;     // P = F S + k_v (J - 1) cof(F)  (Pa)
  T energy_density;  // psi + k_v/2 (J - 1)^2  (J/m^3)
};

// T may be a lane type (cpu_fallback/mls_stress_lanes.h: four particles at once, the coefficients broadcast);
// C is the coefficients' scalar type, so the volume term's switch stays a scalar branch.
template <typename T, typename C>
INC_HD MlsStressPoint<T> mlsStressPoint(const Mat3<T>& g, const MlsCoefficients<C>& c) {
  const Mat3<T> f = Mat3<T>::identity() + g;
  const Mat3<T> e = greenStrain(g);
  const Mat3<T> s = svkStress(e, T(c.mu), T(c.lambda));
  MlsStressPoint<T> out;
  out.piola = f * s;
  out.energy_density = svkEnergyDensity(e, T(c.mu), T(c.lambda));
  if (c.k_volume > C(0)) {
    // psi_v = k_v/2 (J - 1)^2, dpsi_v/dF = k_v (J - 1) cof(F): nearly incompressible tissue and inverted
    // neighbourhoods (J <= 0) are pushed back towards J = 1 instead of collapsing.
    const T jm1 = volumeChange(g);
    out.piola += cofactor(f) * (T(c.k_volume) * jm1);
    out.energy_density += T(0.5) * T(c.k_volume) * jm1 * jm1;
  }
  return out;
}

}  // namespace inc
