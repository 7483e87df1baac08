// Shape-matching terms written for 3-vectors of any type (a CPU vector holding x, y, z in its lanes), with the
// operations and order of clusterFrame, Mat3 * Vec3 and the member passes (the goal and Laplacian corrections for any
// 3-vector type are in physics/pbd_constraints.h).
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
