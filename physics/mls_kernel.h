// MLS kernel weight (eq. 4), moment matrix (eq. 6) and its regularised inverse for degenerate neighbourhoods.
#pragma once

#include <cstdint>

#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc {

// Poly6 kernel of eq. 4, w(r) = 315 / (64 pi h^9) (h^2 - r^2)^3 for r <= h, written as
// 315 / (64 pi h^3) (1 - r^2/h^2)^3 so that h^9 never underflows in float32 (h < 6e-5 m would).
// r2: squared distance (m^2), h: support (m). Units 1/m^3.
template <typename T>
INC_HD T mlsKernelWeight(T r2, T h) {
  const T q2 = r2 / (h * h);
  if (!(q2 < T(1))) return T(0);
  const T a = T(1) - q2;
  const T c = T(315.0 / (64.0 * 3.14159265358979323846)) / (h * h * h);
  return c * a * a * a;
}

// eq. 6: A_i += w_ij x_ij x_ij^T with x_ij = X_j - X_i (rest frame, m).
template <typename T>
INC_HD void accumulateMomentMatrix(Mat3<T>& a, const Vec3<T>& xij, T w) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a.m[r][c] += w * xij[r] * xij[c];
}

// Eigenvalues of a symmetric 3x3 matrix, ascending. The largest comes from the closed trigonometric form;
// the trigonometric form alone loses the small ones near a double root (absolute error ~sqrt(eps) l_max,
// e.g. 1e-8 l_max for a collinear neighbourhood, hiding rank deficiency), so the other two are recovered
// from the invariants: e0 + e1 = tr A - e2 and e0 e1 = det A / e2, solved without cancellation. Then the
// smallest has absolute error ~eps l_max, which is what the rank and condition-number tests need.
template <typename T>
INC_HD void symmetricEigenvalues(const Mat3<T>& a, T& e0, T& e1, T& e2) {
  const T p1 = a.m[0][1] * a.m[0][1] + a.m[0][2] * a.m[0][2] + a.m[1][2] * a.m[1][2];
  const T q = trace(a) / T(3);
  const T d0 = a.m[0][0] - q, d1 = a.m[1][1] - q, d2 = a.m[2][2] - q;
  const T p2 = d0 * d0 + d1 * d1 + d2 * d2 + T(2) * p1;
  if (!(p2 > T(0))) {
    e0 = e1 = e2 = q;
    return;
  }
  const T p = std::sqrt(p2 / T(6));
  Mat3<T> b = a - Mat3<T>::diag(q);
  b *= T(1) / p;
  T r = det(b) / T(2);
  r = r < T(-1) ? T(-1) : (r > T(1) ? T(1) : r);
  const T phi = std::acos(r) / T(3);
  e2 = q + T(2) * p * std::cos(phi);
  if (!(e2 > T(0))) {  // not positive semi-definite with a positive top: plain closed form
    const T two_pi_3 = T(2.0943951023931954923);
    e0 = q + T(2) * p * std::cos(phi + two_pi_3);
    e1 = T(3) * q - e0 - e2;
  } else {
    const T sum = T(3) * q - e2;  // e0 + e1
    const T prod = det(a) / e2;   // e0 e1
    T disc = sum * sum - T(4) * prod;
    disc = disc > T(0) ? disc : T(0);
    const T big = T(0.5) * (sum + (sum >= T(0) ? std::sqrt(disc) : -std::sqrt(disc)));
    e1 = big;
    e0 = big != T(0) ? prod / big : T(0);
  }
  if (e1 < e0) {
    const T t = e0;
    e0 = e1;
    e1 = t;
  }
  if (e2 < e1) {
    const T t = e1;
    e1 = e2;
    e2 = t;
  }
  if (e1 < e0) {
    const T t = e0;
    e0 = e1;
    e1 = t;
  }
}

// Why a neighbourhood got a regularised inverse (bit flags, counted in the metrics).
enum MlsDegeneracy : std::uint8_t {
  kMlsRegular = 0,
  kMlsIsolated = 1,         // no neighbour with positive weight: A_i = 0, gradient defined as 0
  kMlsFewNeighbors = 2,     // fewer than kMlsMinNeighbors weighted neighbours: no redundancy in the fit
  kMlsCoplanar = 4,         // neighbours (numerically) in one plane: A_i has rank 2
  kMlsCollinear = 8,        // neighbours (numerically) on one line: A_i has rank 1
  kMlsIllConditioned = 16,  // cond(A_i) above the limit (includes every rank-deficient case)
};

// Fewer weighted neighbours than this leaves no redundancy in the linear fit of eq. 5.
constexpr int kMlsMinNeighbors = 4;
// Ridge for a few-neighbour particle, as a fraction of the largest eigenvalue of A_i.
constexpr double kMlsFewNeighborRidge = 1.0e-2;

template <typename T>
struct MomentInverse {
  Mat3<T> inverse;     // (A_i + ridge I)^{-1}; zero for an isolated particle
  T condition = T(1);  // cond(A_i) before regularisation (lambda_max / lambda_min; inf when singular)
  T ridge = T(0);      // added to the diagonal (units of A_i: 1/m)
  std::uint8_t flags = kMlsRegular;
};

// The inverse of eq. 6 with Tikhonov regularisation where it is needed: a ridge epsilon on the diagonal
// caps the condition number at `condition_limit` ((l_max + eps) / (l_min + eps) = limit) and, for a
// particle with fewer than kMlsMinNeighbors weighted neighbours, is at least kMlsFewNeighborRidge * l_max.
// A well-conditioned A_i is inverted exactly, so the linear patch test is untouched. Never returns
// NaN or Inf: an empty neighbourhood gives the zero matrix (the particle carries no strain).
template <typename T>
INC_HD MomentInverse<T> regularisedMomentInverse(const Mat3<T>& a, int weighted_neighbors, T condition_limit) {
  MomentInverse<T> out;
  T e0, e1, e2;
  symmetricEigenvalues(a, e0, e1, e2);
  if (weighted_neighbors == 0 || !(e2 > T(0)) || !isFinite(a)) {
    out.flags = kMlsIsolated | kMlsFewNeighbors | kMlsIllConditioned;
    out.condition = T(1) / T(0);  // inf
    return out;                   // inverse stays zero
  }
  const T lmin = e0 > T(0) ? e0 : T(0);
  const T lmid = e1 > T(0) ? e1 : T(0);
  // Rank decisions at a relative tolerance well above rounding of the closed-form eigenvalues.
  const T rank_tol = T(64) * (sizeof(T) == 4 ? T(1.1920929e-7) : T(2.220446049250313e-16)) * e2;
  if (lmid <= rank_tol)
    out.flags |= kMlsCollinear;
  else if (lmin <= rank_tol)
    out.flags |= kMlsCoplanar;
  out.condition = lmin > T(0) ? e2 / lmin : T(1) / T(0);
  T eps = T(0);
  if (!(out.condition <= condition_limit)) {
    out.flags |= kMlsIllConditioned;
    eps = (e2 - condition_limit * lmin) / (condition_limit - T(1));
  }
  if (weighted_neighbors < kMlsMinNeighbors) {
    out.flags |= kMlsFewNeighbors;
    const T few = T(kMlsFewNeighborRidge) * e2;
    eps = eps > few ? eps : few;
  }
  out.ridge = eps;
  const Mat3<T> reg = a + Mat3<T>::diag(eps);
  const T d = det(reg);
  out.inverse = adjugate(reg) * (T(1) / d);
  return out;
}

}  // namespace inc
