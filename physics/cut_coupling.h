// Coupling of the PBD spheres and the MLS nodal points during a cut (section 5.2, eqs. 11-13): per-group math.
#pragma once

#include <cstdint>

#include "physics/hd.h"
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
};

// The sum of the members' displacements over the slots begin + first, begin + first + stride, ... < end: the
// whole sum with (0, 1); a GPU team of `stride` lanes adds its lanes' partial sums (kernels/mls_solver_cuda.cu).
template <typename T>
INC_HD Vec3<T> couplingMemberSum(const Vec3<T>* u, const std::int32_t* members, std::int32_t begin, std::int32_t end,
                                 std::int32_t first, std::int32_t stride) {
  Vec3<T> s;
  for (std::int32_t p = begin + first; p < end; p += stride) s += u[members[p]];
  return s;
}

// eq. 13: the sphere's displacement is the mean displacement of its overlapping points (their sum given).
template <typename T>
INC_HD Vec3<T> couplingMeanOf(const Vec3<T>& sum, std::int32_t begin, std::int32_t end) {
  return end > begin ? sum * (T(1) / T(end - begin)) : sum;
}

template <typename T>
INC_HD Vec3<T> couplingSphereDisplacement(const Vec3<T>* u, const std::int32_t* members, std::int32_t begin,
                                          std::int32_t end) {
  return couplingMeanOf(couplingMemberSum(u, members, begin, end, 0, 1), begin, end);
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

// Group g at the displacement field u: u_a by eq. 13, x_a = C_a + u_a, the springs' total force F_a on it and
// the share of each overlapping point, F_a / n (eq. 12: the energy of eq. 11 averaged over the n points). The
// share is exact: with x_a = C_a + (1/n) sum_i u_i (eq. 13), dE/du_i = (1/n) dE/dx_a, so the points feel the
// negative gradient of the springs' energy and the coupled system has one total energy.
// couplingGroupFinish takes the members' displacement sum (couplingMemberSum), however it was added up.
template <typename T>
INC_HD void couplingGroupFinish(const CouplingView<T>& c, std::int32_t g, const Vec3<T>& member_sum) {
  const std::int32_t b = c.member_offsets[g], e = c.member_offsets[g + 1];
  const Vec3<T> ua = couplingMeanOf(member_sum, b, e);
  c.group_displacement[g] = ua;
  const Vec3<T> xa = c.rest_centre[g] + ua;
  Vec3<T> f;
  for (std::int32_t s = c.spring_offsets[g]; s < c.spring_offsets[g + 1]; ++s)
    f += couplingSpringForce(xa, c.anchor[s], c.rest_length[s], c.stiffness[s]);
  c.member_force[g] = e > b ? f * (T(1) / T(e - b)) : Vec3<T>();
}

template <typename T>
INC_HD void couplingGroupPass(const CouplingView<T>& c, const Vec3<T>* u, std::int32_t g) {
  couplingGroupFinish(c, g, couplingMemberSum(u, c.members, c.member_offsets[g], c.member_offsets[g + 1], 0, 1));
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
