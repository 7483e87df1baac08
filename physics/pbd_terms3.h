// PBD terms (shape matching, Laplacian) written once for 3-vectors of any type (a CPU vector holding x, y, z in its lanes), with the operations and order of clusterFrame, Mat3 * Vec3, projectGoal and laplacianFromSums.
#pragma once

#include "physics/hd.h"
#include "physics/pbd_constraints.h"

namespace inc::pbd {

// One member's term of clusterFrame's centre-of-mass sums: x_cm += x_k m_k and sum m += m_k (before the division).
// V is Vec3<T> or a CPU vector holding x, y, z in its first lanes; the operations and their order per component are
// clusterFrame's, so the sums equal clusterFrame's bit for bit when the members are added in order.
template <typename V, typename T>
INC_HD void clusterCentreTerm3(V& x_cm, T& msum, const V& x, T m) {
  x_cm = x_cm + x * m;
  msum = msum + m;
}

// One member's term of clusterFrame's moment matrix, row by row: row i of A_pq += (d_i r^T) m_k with d = x_k - x_cm
// and r = r_k the member's rest offset (clusterFrame: A_pq += outer(d, r) m_k, element (i, j) = (d_i r_j) m_k).
template <typename V, typename T>
INC_HD void clusterMomentTerm3(V* a_rows, const V& d, const V& r, T m) {
  for (int i = 0; i < 3; ++i) a_rows[i] = a_rows[i] + (r * d[i]) * m;
}

// Mat3 * v for a matrix given by its columns c0, c1, c2 (Mat3 * Vec3: row i = (m_i0 v_x + m_i1 v_y) + m_i2 v_z).
template <typename V>
INC_HD V mulColumns(const V& c0, const V& c1, const V& c2, const V& v) {
  return c0 * v[0] + c1 * v[1] + c2 * v[2];
}

// The three multipliers' updates of a 3-vector constraint value c with one denominator (deltaLambda per component).
// V needs per-component division by a scalar (a CPU vector type).
template <typename V, typename T>
INC_HD V deltaLambda3(const V& c, T w_grad2, const XpbdTerm<T>& term, const V& lambda) {
  const T denom = w_grad2 + term.alpha_tilde;
  V dl{};
  if (denom > T(0)) dl = term.stiffness * (-c - term.alpha_tilde * lambda) / denom;
  return dl;
}

// projectGoal (C = x - goal, three multipliers with one denominator w + alpha~) for a 3-vector type V: the same
// values per component as projectGoal's three deltaLambda calls. Returns dlambda; dp = dlambda w.
template <typename V, typename T>
INC_HD V projectGoal3(const V& x, T w, const V& goal, const XpbdTerm<T>& term, const V& lambda, V& dp) {
  const V dl = deltaLambda3(x - goal, w, term, lambda);
  dp = dl * w;
  return dl;
}

// laplacianFromSums for a 3-vector type (count >= 2): returns dlambda; d_center = dlambda wc, and neighbour j's
// correction is dlambda (-w_j inv_n).
template <typename V, typename T>
INC_HD V laplacianFromSums3(const V& x_center, T wc, const V& mean_sum, T wn, int count, const V& rest_delta_rotated,
                            const XpbdTerm<T>& term, const V& lambda, T& inv_n, V& d_center) {
  inv_n = T(1) / T(count - 1);
  const V mean = mean_sum * inv_n;
  const V c = x_center - mean - rest_delta_rotated;
  const T wg = wc + wn * inv_n * inv_n;
  const V dl = deltaLambda3(c, wg, term, lambda);
  d_center = dl * wc;
  return dl;
}

// shapeMatchMomentumTerm for a 3-vector type: a movable member (w > 0) adds dp (scale m) to the momentum change and
// m to the moving mass.
template <typename V, typename T>
INC_HD void shapeMatchMomentumTerm3(V& dmom, T& mov_mass, const V& dp, T scale, T w, T m) {
  if (!(w > T(0))) return;
  dmom = dmom + dp * (scale * m);
  mov_mass += m;
}

// shapeMatchApplyTerm's correction for a 3-vector type: dp scale + shift for a movable member, else zero (the
// multiplier advances by dlambda scale either way).
template <typename V, typename T>
INC_HD V shapeMatchApplyCorrection3(const V& dp, T scale, T w, const V& shift) {
  return w > T(0) ? dp * scale + shift : V{};
}

}  // namespace inc::pbd
