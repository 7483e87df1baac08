// PBD/XPBD constraint projections: pure functions from positions, inverse masses, rest values and compliance to
// corrections.
#pragma once

#include <cmath>
#include <cstdint>

#include "physics/hd.h"
#include "physics/pbd_rotation.h"
#include "physics/vec3.h"

namespace inc::pbd {

// How strongly one projection acts. XPBD (Macklin et al. 2016): alpha_tilde = alpha / dt^2 with alpha the
// compliance (inverse stiffness, units of the constraint over force), stiffness = 1, lambda accumulated
// over the iterations of one substep. Plain PBD (Mueller et al. 2007): alpha_tilde = 0 and the step is
// scaled by stiffness k in [0, 1] (lambda is still returned but does not feed back).
template <typename T>
struct XpbdTerm {
  T alpha_tilde = T(0);
  T stiffness = T(1);
};

template <typename T>
INC_HD XpbdTerm<T> xpbdTerm(bool xpbd, T compliance, T stiffness, T dt) {
  XpbdTerm<T> t;
  if (xpbd) {
    t.alpha_tilde = compliance / (dt * dt);
    t.stiffness = T(1);
  } else {
    t.alpha_tilde = T(0);
    t.stiffness = stiffness;
  }
  return t;
}

// XPBD multiplier update (Macklin 2016, eq. 18): dlambda = (-C - alpha~ lambda) / (sum_i w_i |grad_i C|^2 + alpha~);
// in PBD mode (alpha~ = 0) this is Mueller 2007's s = -C / sum w |grad C|^2 times k.
template <typename T>
INC_HD T deltaLambda(T c, T w_grad2, const XpbdTerm<T>& term, T lambda) {
  const T denom = w_grad2 + term.alpha_tilde;
  if (!(denom > T(0))) return T(0);  // every participant fixed (w = 0) or a degenerate gradient
  return term.stiffness * (-c - term.alpha_tilde * lambda) / denom;
}

// The three multipliers' updates of a 3-vector constraint value c with one denominator: deltaLambda per component.
// V is Vec3<T> or a CPU vector holding x, y, z in its lanes (needs per-component division by a scalar).
template <typename V, typename T>
INC_HD V deltaLambda3(const V& c, T w_grad2, const XpbdTerm<T>& term, const V& lambda) {
  const T denom = w_grad2 + term.alpha_tilde;
  V dl{};
  if (denom > T(0)) dl = term.stiffness * (-c - term.alpha_tilde * lambda) / denom;
  return dl;
}

// ---------------------------------------------------------------------------------------------
// Distance / stretch: C = |p0 - p1| - d (metaballs paper eq. 1, tresca paper eq. 1). With w = 1/m, k = 1 and
// alpha = 0 the corrections are the paper's eqs. 2-3: dp0 = -w0/(w0+w1) C n = -m1/(m0+m1) C n, dp1 = +m0/(m0+m1) C n.
template <typename T>
struct DistanceCorrection {
  Vec3<T> dp0, dp1;
  T dlambda = T(0);
  T c = T(0);  // constraint value before the correction (m)
};

template <typename T>
INC_HD DistanceCorrection<T> projectDistance(const Vec3<T>& p0, const Vec3<T>& p1, T w0, T w1, T rest,
                                             const XpbdTerm<T>& term, T lambda) {
  DistanceCorrection<T> out;
  const Vec3<T> d = p0 - p1;
  const T len = norm(d);
  out.c = len - rest;
  if (!(len > T(0))) return out;  // coincident centres: the direction is undefined, skip this pass
  const Vec3<T> n = d * (T(1) / len);
  out.dlambda = deltaLambda(out.c, w0 + w1, term, lambda);
  out.dp0 = n * (w0 * out.dlambda);
  out.dp1 = n * (-w1 * out.dlambda);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Dihedral bending on two triangles (p0, p2, p1) and (p0, p1, p3) sharing the edge p0-p1 (tresca paper eq. 2
// with its p1..p4 renamed p0..p3). The paper writes C = acos(n1 . n2) - phi0 with n1 ~ e x (p2 - p0),
// n2 ~ e x (p3 - p0), e = p1 - p0. That form is unsigned and its gradient is undefined where n1 . n2 = +-1,
// i.e. exactly at the flat rest state of a sheet (phi = pi). We use the signed angle psi in [0, 2 pi) from n1
// to n2 about e, psi = atan2((n1 x n2) . e/|e|, n1 . n2), whose value equals the paper's acos(n1 . n2) for
// psi <= pi and which is smooth through the flat state; C = psi - psi0.
template <typename T>
struct BendingCorrection {
  Vec3<T> dp[4];
  T dlambda = T(0);
  T c = T(0);  // rad
};

template <typename T>
INC_HD T dihedralAngle(const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2, const Vec3<T>& p3) {
  const Vec3<T> e = p1 - p0;
  const Vec3<T> n1 = cross(e, p2 - p0), n2 = cross(e, p3 - p0);
  const T le = norm(e);
  if (!(le > T(0))) return T(0);
  const T s = dot(cross(n1, n2), e) / le, c = dot(n1, n2);
  T psi = std::atan2(s, c);
  const T two_pi = T(6.283185307179586);
  if (psi < T(0)) psi += two_pi;
  return psi;
}

// Gradients of psi: the wing vertices move the angle by rotating their triangle about the edge,
// dpsi/dp2 = -|e| n1/|n1|^2, dpsi/dp3 = +|e| n2/|n2|^2; the edge ends share the wing gradients in proportion to
// where each wing's foot lies along the edge (translation invariance: the four gradients sum to zero).
template <typename T>
INC_HD bool dihedralGradients(const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2, const Vec3<T>& p3,
                              Vec3<T> g[4]) {
  const Vec3<T> e = p1 - p0;
  const Vec3<T> n1 = cross(e, p2 - p0), n2 = cross(e, p3 - p0);
  const T le2 = norm2(e), n1l2 = norm2(n1), n2l2 = norm2(n2);
  const T tiny = sizeof(T) == 4 ? T(1e-20) : T(1e-40);
  if (!(le2 > tiny) || !(n1l2 > tiny * le2) || !(n2l2 > tiny * le2)) return false;  // degenerate triangle
  const T le = std::sqrt(le2);
  g[2] = n1 * (-le / n1l2);
  g[3] = n2 * (le / n2l2);
  const T s2 = dot(p2 - p0, e) / le2, s3 = dot(p3 - p0, e) / le2;  // foot positions along the edge, 0 at p0
  g[1] = -(g[2] * s2 + g[3] * s3);
  g[0] = -(g[2] * (T(1) - s2) + g[3] * (T(1) - s3));
  return true;
}

template <typename T>
INC_HD BendingCorrection<T> projectBending(const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2, const Vec3<T>& p3,
                                           T w0, T w1, T w2, T w3, T rest_angle, const XpbdTerm<T>& term, T lambda) {
  BendingCorrection<T> out;
  Vec3<T> g[4];
  if (!dihedralGradients(p0, p1, p2, p3, g)) return out;
  out.c = dihedralAngle(p0, p1, p2, p3) - rest_angle;
  const T w[4] = {w0, w1, w2, w3};
  T wg = T(0);
  for (int k = 0; k < 4; ++k) wg += w[k] * norm2(g[k]);
  out.dlambda = deltaLambda(out.c, wg, term, lambda);
  for (int k = 0; k < 4; ++k) out.dp[k] = g[k] * (w[k] * out.dlambda);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Tetrahedral volume: C = (1/6) (p1 - p0) x (p2 - p0) . (p3 - p0) - V0 (signed volume, m^3).
template <typename T>
struct TetVolumeCorrection {
  Vec3<T> dp[4];
  T dlambda = T(0);
  T c = T(0);
};

template <typename T>
INC_HD T tetSignedVolume(const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2, const Vec3<T>& p3) {
  return dot(cross(p1 - p0, p2 - p0), p3 - p0) / T(6);
}

template <typename T>
INC_HD TetVolumeCorrection<T> projectTetVolume(const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2,
                                               const Vec3<T>& p3, T w0, T w1, T w2, T w3, T rest_volume,
                                               const XpbdTerm<T>& term, T lambda) {
  TetVolumeCorrection<T> out;
  Vec3<T> g[4];
  g[1] = cross(p2 - p0, p3 - p0) * (T(1) / T(6));
  g[2] = cross(p3 - p0, p1 - p0) * (T(1) / T(6));
  g[3] = cross(p1 - p0, p2 - p0) * (T(1) / T(6));
  g[0] = -(g[1] + g[2] + g[3]);
  out.c = tetSignedVolume(p0, p1, p2, p3) - rest_volume;
  const T w[4] = {w0, w1, w2, w3};
  T wg = T(0);
  for (int k = 0; k < 4; ++k) wg += w[k] * norm2(g[k]);
  out.dlambda = deltaLambda(out.c, wg, term, lambda);
  for (int k = 0; k < 4; ++k) out.dp[k] = g[k] * (w[k] * out.dlambda);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Laplacian coordinate of a sphere on the link graph (Sorkine et al. 2004, the metaballs paper's [24]):
// delta_i = c_i - (1/n) sum_{j in N(i)} c_j. The constraint keeps it at its rest value, carried along by the
// neighbourhood's rotation R_i (from shape matching) so that a rigid rotation of the organ is not resisted:
// C_i = delta_i - R_i delta_i^0 (a 3-vector: three scalar constraints sharing one gradient,
// dC/dc_i = I, dC/dc_j = -I/n). Its multiplier lambda is a 3-vector too.
template <typename T>
struct LaplacianCorrection {
  Vec3<T> d_center;  // correction of c_i
  Vec3<T> dlambda;   // correction of c_j (j in N(i)) is -w_j / n * dlambda
  T inv_n = T(0);
  Vec3<T> c;  // constraint value before the correction (m)
};

// The Laplacian correction from the sums over the neighbours (mean_sum = sum_j x_j, wn = sum_j w_j over the
// count - 1 neighbours): the serial loop below and the CUDA group projection (kernels/pbd_group_projection.cuh)
// both reduce to these sums and finish here.
// For any 3-vector type V (count >= 2): returns dlambda; d_center = dlambda wc, and neighbour j's correction is
// dlambda (-w_j inv_n).
template <typename V, typename T>
INC_HD V laplacianFromSums3(const V& x_center, T wc, const V& mean_sum, T wn, int count, const V& rest_delta_rotated,
                            const XpbdTerm<T>& term, const V& lambda, T& inv_n, V& d_center, V* c_out = nullptr) {
  inv_n = T(1) / T(count - 1);
  const V mean = mean_sum * inv_n;
  const V c = x_center - mean - rest_delta_rotated;
  if (c_out) *c_out = c;
  const T wg = wc + wn * inv_n * inv_n;
  const V dl = deltaLambda3(c, wg, term, lambda);
  d_center = dl * wc;
  return dl;
}

template <typename T>
INC_HD LaplacianCorrection<T> laplacianFromSums(const Vec3<T>& x_center, T wc, const Vec3<T>& mean_sum, T wn, int count,
                                                const Vec3<T>& rest_delta_rotated, const XpbdTerm<T>& term,
                                                const Vec3<T>& lambda) {
  LaplacianCorrection<T> out;
  if (count < 2) return out;
  out.dlambda = laplacianFromSums3(x_center, wc, mean_sum, wn, count, rest_delta_rotated, term, lambda, out.inv_n,
                                   out.d_center, &out.c);
  return out;
}

// ids[0] is the centre sphere, ids[1..count) its neighbours.
template <typename T>
INC_HD LaplacianCorrection<T> projectLaplacian(const Vec3<T>* x, const T* w, const std::int32_t* ids, int count,
                                               const Vec3<T>& rest_delta_rotated, const XpbdTerm<T>& term,
                                               const Vec3<T>& lambda) {
  if (count < 2) return LaplacianCorrection<T>();
  Vec3<T> mean_sum;
  T wn = T(0);
  for (int k = 1; k < count; ++k) {
    mean_sum += x[ids[k]];
    wn += w[ids[k]];
  }
  return laplacianFromSums(x[ids[0]], w[ids[0]], mean_sum, wn, count, rest_delta_rotated, term, lambda);
}

// ---------------------------------------------------------------------------------------------
// Shape matching of one sphere's neighbourhood (Mueller et al. 2005 meshless shape matching, on the cluster
// {i} u N(i)). q_k = r_k - r_cm are the members' rest offsets from the rest centre of mass; the moment matrix
// A_pq = sum_k m_k (x_k - x_cm) q_k^T; its rotational part R (polar decomposition) gives goal positions
// g_k = R q_k + x_cm. The per-sphere rotation R is what the skinning uses.
template <typename T>
struct ClusterFrame {
  Vec3<T> x_cm;
  Mat3<T> a_pq;
};

template <typename T>
INC_HD ClusterFrame<T> clusterFrame(const Vec3<T>* x, const T* m, const std::int32_t* ids, const Vec3<T>* rest_offsets,
                                    int count) {
  ClusterFrame<T> f;
  T msum = T(0);
  for (int k = 0; k < count; ++k) {
    f.x_cm += x[ids[k]] * m[ids[k]];
    msum += m[ids[k]];
  }
  if (msum > T(0)) f.x_cm *= T(1) / msum;
  for (int k = 0; k < count; ++k) f.a_pq += outer(x[ids[k]] - f.x_cm, rest_offsets[k]) * m[ids[k]];
  return f;
}

// Each member is pulled towards its goal by a zero-rest-length compliant constraint C = x_k - g_k (3-vector;
// the goal is held fixed during the projection, as in shape matching). Returns the correction of x_k and the
// multiplier update.
template <typename T>
struct GoalCorrection {
  Vec3<T> dp;
  Vec3<T> dlambda;
  Vec3<T> c;
};

// For any 3-vector type V: returns dlambda; dp = dlambda w.
template <typename V, typename T>
INC_HD V projectGoal3(const V& x, T w, const V& goal, const XpbdTerm<T>& term, const V& lambda, V& dp) {
  const V dl = deltaLambda3(x - goal, w, term, lambda);
  dp = dl * w;
  return dl;
}

template <typename T>
INC_HD GoalCorrection<T> projectGoal(const Vec3<T>& x, T w, const Vec3<T>& goal, const XpbdTerm<T>& term,
                                     const Vec3<T>& lambda) {
  GoalCorrection<T> out;
  out.c = x - goal;
  out.dlambda = projectGoal3(x, w, goal, term, lambda, out.dp);
  return out;
}

}  // namespace inc::pbd
