// Coupling of the PBD spheres and the MLS nodal points during a cut (section 5.2, eqs. 11-13): per-group math.
#pragma once

#include <cstdint>

#include "physics/hd.h"
#include "physics/pbd_rotation.h"
#include "physics/vec3.h"

namespace inc {

// A coupling group is one converted sphere a: its nodal ("overlapping") points, its rest centre C_a and the
// springs that linked it to spheres still simulated by PBD (anchors). CSR over groups; all positions are
// relative to the MLS model origin (m). Held constant over one coupling exchange except the outputs.
template <typename T>
struct CouplingView {
  std::int32_t groups = 0;
  const std::int32_t* member_offsets = nullptr;  // group g's particles: members[member_offsets[g] .. [g+1])
  const std::int32_t* members = nullptr;
  const Vec3<T>* rest_centre = nullptr;          // C_a (m)
  const std::int32_t* spring_offsets = nullptr;  // group g's springs: [spring_offsets[g] .. [g+1])
  const Vec3<T>* anchor = nullptr;               // x_j of the spring's PBD sphere (m), per spring
  const T* rest_length = nullptr;                // l_ja (m), per spring
  const T* stiffness = nullptr;                  // k_ja (N/m), per spring
  Vec3<T>* group_displacement = nullptr;         // out: u_a of eq. 13 (m)
  Vec3<T>* member_force = nullptr;               // out: force on each member of the group (N), eq. 12
  // Rotation-aware eq. 13 (couplingGroupFinish); rest_centroid null: every group follows the plain mean.
  const Vec3<T>* member_rest = nullptr;      // rest position X_i of every particle (m), indexed by particle
  const Vec3<T>* rest_centroid = nullptr;    // Xbar_a, the mean of the group's member rest positions (m)
  const Mat3<T>* rest_gram = nullptr;        // Q_a = sum q q^T, q = X_i - Xbar_a (m^2)
  const Mat3<T>* inertia_inverse = nullptr;  // J_a^-1, J_a = sum (|q|^2 I - q q^T) (1/m^2); zero: no rotation
  pbd::Quat<T>* rotation = nullptr;          // in/out: the group's best-fit rotation (the warm start)
  Mat3<T>* member_torque = nullptr;          // out: member i's force is member_force + member_torque (X_i - Xbar_a)
};

// Whether group g follows the rotation-aware eq. 13: the view carries the rest frames and the group's points span
// a volume (mlsCouplingFrames leaves a zero inverse where they are too few or too close to a line).
template <typename T>
INC_HD bool couplingRotates(const CouplingView<T>& c, std::int32_t g) {
  return c.rest_centroid != nullptr && trace(c.inertia_inverse[g]) > T(0);
}

// The sums a group's eq. 13 needs over its member slots first, first + stride, ...: the members' displacements and,
// for a rotating group, sum u_i q_i^T (q_i = X_i - Xbar_a). The whole sums with (0, 1); a GPU team of `stride` lanes
// adds its lanes' partial sums (kernels/mls_solver_cuda.cu).
template <typename T>
struct CouplingSums {
  Vec3<T> u;
  Mat3<T> uq;
};
template <typename T>
INC_HD CouplingSums<T> couplingMemberSums(const CouplingView<T>& c, const Vec3<T>* u, std::int32_t g,
                                          std::int32_t first, std::int32_t stride) {
  CouplingSums<T> s;
  const std::int32_t begin = c.member_offsets[g], end = c.member_offsets[g + 1];
  const bool rotates = couplingRotates(c, g);
  for (std::int32_t p = begin + first; p < end; p += stride) {
    const std::int32_t i = c.members[p];
    s.u += u[i];
    if (rotates) s.uq += outer(u[i], c.member_rest[i] - c.rest_centroid[g]);
  }
  return s;
}

// The paper's eq. 13: the sphere's displacement is the mean displacement of its overlapping points (their sum given).
template <typename T>
INC_HD Vec3<T> couplingMeanOf(const Vec3<T>& sum, std::int32_t begin, std::int32_t end) {
  return end > begin ? sum * (T(1) / T(end - begin)) : sum;
}

// The same from the displacements of members[begin .. end): what a group without rest frames follows, and the
// reference the tests compare the rotation-aware eq. 13 with.
template <typename T>
INC_HD Vec3<T> couplingSphereDisplacement(const Vec3<T>* u, const std::int32_t* members, std::int32_t begin,
                                          std::int32_t end) {
  Vec3<T> sum;
  for (std::int32_t p = begin; p < end; ++p) sum += u[members[p]];
  return couplingMeanOf(sum, begin, end);
}

// The force on sphere a (at x_a) of the spring a-j (x_j, rest length l, stiffness k): -dE/dx_a of
// E = k/2 (|x_a - x_j| - l)^2, the Hooke energy of eq. 11. Eq. 11 also weights each term by m_j / (m_a + m_j):
// that is the share of a PBD projection that moves sphere a, not part of the spring's energy; the full
// gradient keeps action = reaction with the PBD side (docs/cutting.md). Zero for coincident ends.
template <typename T>
INC_HD Vec3<T> couplingSpringForce(const Vec3<T>& xa, const Vec3<T>& xj, T rest, T k) {
  const Vec3<T> d = xj - xa;
  const T len = norm(d);
  if (!(len > T(0))) return Vec3<T>();
  return d * (k * (len - rest) / len);
}

// E = k/2 (l' - l)^2 (J), the spring's stored energy (eq. 11 without the PBD share factor).
template <typename T>
INC_HD T couplingSpringEnergy(const Vec3<T>& xa, const Vec3<T>& xj, T rest, T k) {
  const T e = norm(xj - xa) - rest;
  return T(0.5) * k * e * e;
}

// Steps for a group's rotation when it starts from the identity (a new group): up to this many. Warm-started from
// the last evaluation (every substep) a group takes one Newton step, whose residual is about the square of its turn
// per substep (1e-3 rad -> 1e-6 rad): a second step would only confirm convergence, and on the CPU the steps had
// made the cutting frame's MLS part 20 % longer.
constexpr int kCouplingRotationSteps = 16;

// One step towards the rotation R that maximises tr(R^T A) (the best-fit rotation of Kabsch), updating q; false
// when converged. Why not pbd::extractRotationStep: its step divides the gradient by the scalar tr(R^T A), which
// converges slowly where A is far from isotropic, as the second moment of a lens of points is (measured: 3e-4 rad
// left of a 0.1 rad turn after 16 steps). Near the optimum this takes the Newton step with the Hessian R (tr(S) I -
// S) R^T (S the symmetric part of R^T A; at a rigid configuration that is R J_a R^T), quadratically convergent;
// where that is not positive definite (far from the optimum) it takes the scaled gradient step of Mueller et al.
// (at most a quarter turn).
template <typename T>
INC_HD bool couplingRotationStep(const Mat3<T>& a, T scale, pbd::Quat<T>& q) {
  // Converged below this angle (rad). float32: the rounding of A alone moves the Newton step by ~5e-6 rad where J_a
  // is anisotropic (its smallest eigenvalue down to kCouplingMinInertiaRatio of its trace), so a tighter bound would
  // spend every step of every substep chasing noise; 2e-5 rad moves a sphere 5 mm from the centroid by 0.1 um.
  const T eps = sizeof(T) == 4 ? T(2e-5) : T(1e-12);
  const Mat3<T> r = pbd::quatToMatrix(q);
  const Vec3<T> grad = cross(r.col(0), a.col(0)) + cross(r.col(1), a.col(1)) + cross(r.col(2), a.col(2));
  Mat3<T> s = transpose(r) * a;
  s = (s + transpose(s)) * T(0.5);
  const Mat3<T> h = Mat3<T>::diag(trace(s)) - s;
  const T d = det(h), minor2 = h.m[0][0] * h.m[1][1] - h.m[0][1] * h.m[1][0];
  Vec3<T> step;
  if (h.m[0][0] > T(0) && minor2 > T(0) && d > eps * scale * scale * scale)
    step = r * (adjugate(h) * (transpose(r) * grad)) * (T(1) / d);
  else
    step = grad * (T(1) / (std::fabs(trace(s)) + eps * scale));
  T angle = norm(step);
  // Far from the optimum tr(S) can vanish and the scaled step overshoot: at most a quarter turn per step.
  if (angle > T(0.785)) {
    step *= T(0.785) / angle;
    angle = T(0.785);
  }
  if (!(angle > eps)) return false;
  q = pbd::quatNormalized(pbd::quatMul(pbd::quatFromAxisAngle(step * (T(1) / angle), angle), q));
  return true;
}

template <typename T>
INC_HD pbd::Quat<T> couplingBestRotation(const Mat3<T>& a, pbd::Quat<T> q, int max_steps) {
  const T scale = frobeniusNorm(a);
  if (!(scale > T(0))) return q;
  for (int it = 0; it < max_steps; ++it)
    if (!couplingRotationStep(a, scale, q)) break;
  return q;
}

// Group g at the displacement field u: u_a by eq. 13, x_a = C_a + u_a, the springs' total force F_a on it and
// each overlapping point's share (eq. 12: the energy of eq. 11 distributed over the n points), from the sums of
// couplingMemberSums however they were added up.
//
// The paper's eq. 13 moves the sphere by the mean displacement of its points. That is exact for translations only:
// the points of a group are the part of the sphere that overlaps the cut spheres, off its centre, and a rotation R
// of the group moves x_a by (R - I)(Xbar_a - C_a) too far (a lie under a flap that turns). A rotating group takes
// the best-fit rigid motion of its points instead (Kabsch: R the rotational part of A = sum (x_i - xbar) q_i^T =
// Q_a + sum u_i q_i^T), x_a = xbar + R (C_a - Xbar_a): exact for any rigid motion, and the plain mean at rest and
// for translations. The share is the chain rule of that map at a rigid configuration: with w = R (C_a - Xbar_a) the
// springs' moment about the centroid, tau = w x F_a, is carried by the points as a rigid body with unit weights,
// f_i = F_a / n + alpha x (R q_i), alpha = (R J_a R^T)^-1 tau, so the points receive exactly F_a and tau. A group
// without rest frames follows the plain mean, where dE/du_i = (1/n) dE/dx_a holds exactly (docs/cutting.md).
template <typename T>
INC_HD void couplingGroupFinish(const CouplingView<T>& c, std::int32_t g, const CouplingSums<T>& sums) {
  const std::int32_t b = c.member_offsets[g], e = c.member_offsets[g + 1];
  Vec3<T> ua = couplingMeanOf(sums.u, b, e);
  const bool rotates = couplingRotates(c, g);
  Mat3<T> rot = Mat3<T>::identity();
  Vec3<T> lever;
  if (rotates) {
    const pbd::Quat<T> q0 = c.rotation[g];
    const bool fresh = q0.w == T(1) && q0.x == T(0) && q0.y == T(0) && q0.z == T(0);
    const pbd::Quat<T> q = couplingBestRotation(c.rest_gram[g] + sums.uq, q0, fresh ? kCouplingRotationSteps : 1);
    c.rotation[g] = q;
    rot = pbd::quatToMatrix(q);
    const Vec3<T> r = c.rest_centre[g] - c.rest_centroid[g];
    lever = rot * r;
    ua += lever - r;  // (R - I) r: exactly zero at R = I, so a group at rest or translated keeps the plain mean
  }
  c.group_displacement[g] = ua;
  const Vec3<T> xa = c.rest_centre[g] + ua;
  Vec3<T> f;
  for (std::int32_t s = c.spring_offsets[g]; s < c.spring_offsets[g + 1]; ++s)
    f += couplingSpringForce(xa, c.anchor[s], c.rest_length[s], c.stiffness[s]);
  c.member_force[g] = e > b ? f * (T(1) / T(e - b)) : Vec3<T>();
  if (c.member_torque) {
    Mat3<T> torque;
    if (rotates) {
      const Vec3<T> alpha = rot * (c.inertia_inverse[g] * (transpose(rot) * cross(lever, f)));
      // alpha x (R q) for every q: the skew matrix of alpha times R.
      const Mat3<T> skew = Mat3<T>::fromRows(Vec3<T>(T(0), -alpha.z, alpha.y), Vec3<T>(alpha.z, T(0), -alpha.x),
                                             Vec3<T>(-alpha.y, alpha.x, T(0)));
      torque = skew * rot;
    }
    c.member_torque[g] = torque;
  }
}

template <typename T>
INC_HD void couplingGroupPass(const CouplingView<T>& c, const Vec3<T>* u, std::int32_t g) {
  couplingGroupFinish(c, g, couplingMemberSums(c, u, g, 0, 1));
}

// The force on particle i, member of group g, from its group (eq. 12 with the moment of the rotation-aware eq. 13).
template <typename T>
INC_HD Vec3<T> couplingMemberForce(const Vec3<T>& share, const Mat3<T>* torque, const Vec3<T>* centroid,
                                   const Vec3<T>& rest_i, std::int32_t g) {
  return torque ? share + torque[g] * (rest_i - centroid[g]) : share;
}

// The largest angular frequency (rad/s) of a group's rigid mode on its springs: sqrt(sum k / m_group). An
// explicit step of the points must stay below 2 / omega for the springs as for the elastic forces.
template <typename T>
INC_HD T couplingGroupOmega(const T* stiffness, std::int32_t spring_begin, std::int32_t spring_end, T group_mass) {
  T k = T(0);
  for (std::int32_t s = spring_begin; s < spring_end; ++s) k += stiffness[s];
  return group_mass > T(0) ? std::sqrt(k / group_mass) : T(0);
}

}  // namespace inc
