// The per-particle bodies of the MLS step (drift, pass 1 stress, pass 2 force gather + kick) that the CPU
// loops and the CUDA kernels both call, over raw SoA pointers.
#pragma once

#include <cstdint>

#include "physics/cut_coupling.h"
#include "physics/hd.h"
#include "physics/mls_blade_contact.h"
#include "physics/mls_elasticity.h"
#include "physics/mls_integrate.h"
#include "physics/mls_kernel.h"
#include "physics/mls_static_contact.h"
#include "physics/vec3.h"

namespace inc {

// Raw views of one MLS model + state (host or device memory alike). Rest neighbourhoods are symmetric
// (one support radius h, closed ball decided by distance2Exact), which makes pass 2 a pure gather.
template <typename T>
struct MlsView {
  std::int64_t n = 0;
  // model (rest configuration)
  const Vec3<T>* rest = nullptr;            // X_i relative to the model origin (m)
  const T* mass = nullptr;                  // kg
  const T* volume = nullptr;                // rest volume v_i (m^3)
  const Mat3<T>* moment_inverse = nullptr;  // regularised A_i^{-1} (m)
  const std::uint8_t* kind = nullptr;       // MlsParticleKind
  const std::int64_t* offsets = nullptr;    // CSR rest neighbourhoods
  const std::int32_t* indices = nullptr;
  T support = T(0);  // h (m)
  MlsCoefficients<T> coeffs;
  Vec3<T> gravity;  // m/s^2
  // state
  Vec3<T>* displacement = nullptr;  // u_i (m)
  Vec3<T>* velocity = nullptr;      // m/s
  Vec3<T>* force = nullptr;         // elastic force f_i (N), at the current displacement
  const Vec3<T>* target = nullptr;  // prescribed displacement at the end of the frame (m)
  // pass-1 output consumed by pass 2
  Mat3<T>* stress_moment = nullptr;  // M_i = v_i P_i A_i^{-1} (N m^2)
  T* energy = nullptr;               // v_i psi_i (J)
  // Optional coupling to PBD spheres (physics/cut_coupling.h): particle k's group (-1: none) and each group's
  // force per member (N), recomputed from the displacement before every force pass. Null: no coupling.
  const std::int32_t* coupling_group = nullptr;
  const Vec3<T>* coupling_force = nullptr;
  // A rotating group's moment (CouplingView::member_torque, rest_centroid): member k's share is coupling_force +
  // coupling_torque (X_k - centroid). Null: every share is coupling_force alone.
  const Mat3<T>* coupling_torque = nullptr;
  const Vec3<T>* coupling_centroid = nullptr;
  // Optional pair tables of the rest configuration (mlsPairTerms; the CPU fallback builds them, the CUDA kernels
  // pass null and recompute from the rest positions, which costs them less than the traffic). Per CSR slot p of
  // particle i with neighbour j: pair_gradient[p] = w_ij A_i^{-T} x_ij, pair_force[p] = w_ij x_ij; weighted_sum[i]
  // = sum_j w_ij x_ij. With them a pass reads no rest position and evaluates no kernel weight.
  const Vec3<T>* pair_gradient = nullptr;
  const Vec3<T>* pair_force = nullptr;
  const Vec3<T>* weighted_sum = nullptr;
  // Optional outputs: the stress pass's mlsStiffening of the gradient it computed, the force pass's elastic part
  // of the force (without the coupling share; mlsCouplingRefresh adds a new share to it). Null: not written.
  T* stiffening = nullptr;
  Vec3<T>* elastic_force = nullptr;
  // Optional scalpel contact (physics/mls_blade_contact.h), applied to free particles in every drift. Null: none.
  const MlsBladeContact<T>* blade = nullptr;
  // Optional static colliders (physics/mls_static_contact.h), applied to free particles after the blade. Null: none.
  const MlsStaticContacts<T>* statics = nullptr;
};

// The rest-configuration terms of one pair (i, j) that the passes use (x_ij = X_j - X_i, w_ij its eq. 4 weight):
// d = w_ij A_i^{-T} x_ij, so that eq. 5 reads G_i = sum_j (u_j - u_i) d^T, and wx = w_ij x_ij for eq. 9.
template <typename T>
INC_HD void mlsPairTerms(const Mat3<T>& moment_inverse, const Vec3<T>& xij, T w, Vec3<T>& d, Vec3<T>& wx) {
  wx = xij * w;
  for (int c = 0; c < 3; ++c)
    d[c] = wx[0] * moment_inverse.m[0][c] + wx[1] * moment_inverse.m[1][c] + wx[2] * moment_inverse.m[2][c];
}

// The bracket of eq. 5 over the slots offsets[i] + first, + first + stride, ... (without pair tables): the whole
// sum with (0, 1); a GPU team of `stride` lanes adds its lanes' partial sums before the product with A_i^{-1}.
template <typename T>
INC_HD Mat3<T> mlsGradientPairSum(const MlsView<T>& s, std::int64_t i, int first, int stride) {
  const Vec3<T> xi = s.rest[i], ui = s.displacement[i];
  Mat3<T> b;
  for (std::int64_t p = s.offsets[i] + first; p < s.offsets[i + 1]; p += stride) {
    const std::int32_t j = s.indices[p];
    const Vec3<T> xij = s.rest[j] - xi;
    const T w = mlsKernelWeight(norm2(xij), s.support);
    accumulateGradient(b, s.displacement[j] - ui, xij, w);
  }
  return b;
}

// eq. 5: G_i = [sum_j w_ij (u_j - u_i) x_ij^T] A_i^{-1}, x_ij = X_j - X_i.
// With the pair tables: the same sum as sum_j (u_j - u_i) (w_ij x_ij^T A_i^{-1}), one product less per pair,
// in two running sums (the even and the odd slots of the list, added at the end: two independent addition
// chains for the CPU's vector loop, cpu_fallback/mls_pair_sums_cpu.cpp, which reproduces this order).
template <typename T>
INC_HD Mat3<T> mlsDisplacementGradient(const MlsView<T>& s, std::int64_t i) {
  const Vec3<T> ui = s.displacement[i];
  if (s.pair_gradient) {
    Mat3<T> g, g_odd;
    const std::int64_t e = s.offsets[i + 1];
    std::int64_t p = s.offsets[i];
    for (; p + 1 < e; p += 2) {
      accumulateGradient(g, s.displacement[s.indices[p]] - ui, s.pair_gradient[p], T(1));
      accumulateGradient(g_odd, s.displacement[s.indices[p + 1]] - ui, s.pair_gradient[p + 1], T(1));
    }
    if (p < e) accumulateGradient(g, s.displacement[s.indices[p]] - ui, s.pair_gradient[p], T(1));
    g += g_odd;
    return g;
  }
  return mlsGradientPairSum(s, i, 0, 1) * s.moment_inverse[i];
}

// How much stiffer than at rest the material is at gradient G: SVK's tangent modulus along the most
// stretched direction grows like (3 c - 1) / 2 with c the largest eigenvalue of C = F^T F (uniaxial SVK:
// dP/dlambda = E (3 lambda^2 - 1) / 2), the volume penalty's like c^2. c is the eigenvalue itself (closed
// form, symmetricEigenvalues), capped by its Gershgorin bound, the largest absolute row sum of C. Until
// 2026-11-26 the bound alone was used: it over-estimates sheared states (~10 % more substeps in the cutting
// benchmark for nothing). The cap keeps a rigid rotation at exactly 1 (C = I to rounding, where the closed
// form's near-triple root is only sqrt(eps) accurate). The stable step shrinks by sqrt of the largest factor
// (the rest-state limit assumes 1). Returns >= 1.
template <typename T>
INC_HD T mlsStiffeningOf(const Mat3<T>& g, const MlsCoefficients<T>& coeffs) {
  const Mat3<T> f = Mat3<T>::identity() + g;
  const Mat3<T> c = transpose(f) * f;
  T cmax = T(0);
  for (int r = 0; r < 3; ++r) {
    const T row = std::fabs(c.m[r][0]) + std::fabs(c.m[r][1]) + std::fabs(c.m[r][2]);
    cmax = row > cmax ? row : cmax;
  }
  T e0, e1, e2;
  symmetricEigenvalues(c, e0, e1, e2);
  cmax = e2 < cmax ? e2 : cmax;
  const T svk = T(0.5) * (T(3) * cmax - T(1));
  const T vol = coeffs.k_volume > T(0) ? cmax * cmax : T(1);
  const T k = svk > vol ? svk : vol;
  return k > T(1) ? k : T(1);
}

// Pass 1 at particle i: gradient, strain, stress, energy; stores M_i = v_i P_i A_i^{-1} for pass 2.
// Split in two so that a CPU loop may form the gradient's pair sum its own way (the same sums, in the same
// order: cpu_fallback/mls_pair_sums_cpu.cpp) and call the rest from here.
// What pass 1 stores of a particle of volume v from its stress point: M = v P A^{-1} and its energy v psi.
// T may be a lane type (cpu_fallback/mls_stress_lanes.h).
template <typename T>
INC_HD void mlsStressOutputs(const MlsStressPoint<T>& sp, const T& v, const Mat3<T>& moment_inverse, Mat3<T>& moment,
                             T& energy) {
  moment = (sp.piola * v) * moment_inverse;
  energy = v * sp.energy_density;
}

template <typename T>
INC_HD void mlsStressAt(const MlsView<T>& s, std::int64_t i, const Mat3<T>& g) {
  mlsStressOutputs(mlsStressPoint(g, s.coeffs), s.volume[i], s.moment_inverse[i], s.stress_moment[i], s.energy[i]);
  if (s.stiffening) s.stiffening[i] = mlsStiffeningOf(g, s.coeffs);
}

template <typename T>
INC_HD void mlsStressPass(const MlsView<T>& s, std::int64_t i) {
  mlsStressAt(s, i, mlsDisplacementGradient(s, i));
}

// eq. 9, exact negative gradient of U = sum_i v_i psi_i with d_ij = w_ij A_i^{-1} x_ij:
//   f_k = v_k P_k sum_j d_kj - sum_{i in N(k)} v_i P_i d_ik = sum_{i in N(k)} w_ki (M_k + M_i)(X_i - X_k).
// Each pair term is antisymmetric in (k, i), so momentum is conserved pair by pair.
// With the pair tables: f_k = M_k sum_i w_ki x_ki + sum_i M_i w_ki x_ki (the same sum, split). The second sum
// is kept entry by entry, a_rc = sum_i (M_i)_rc (w_ki x_ki)_c, over the even and the odd slots apart (added at
// the end), and each row summed last: nine running sums twice, the order the CPU's vector loop reproduces lane
// for lane (cpu_fallback/mls_pair_sums_cpu.cpp).
template <typename T>
INC_HD Vec3<T> mlsForceFromPairSum(const Mat3<T>& mk, const Vec3<T>& weighted_sum, const Mat3<T>& a) {
  Vec3<T> f = mk * weighted_sum;
  for (int r = 0; r < 3; ++r) f[r] += (a.m[r][0] + a.m[r][1]) + a.m[r][2];
  return f;
}

// eq. 9's sum over the slots offsets[k] + first, + first + stride, ... (without pair tables): the whole force with
// (0, 1); a GPU team of `stride` lanes adds its lanes' partial sums.
template <typename T>
INC_HD Vec3<T> mlsForcePairSum(const MlsView<T>& s, std::int64_t k, int first, int stride) {
  const Mat3<T> mk = s.stress_moment[k];
  const Vec3<T> xk = s.rest[k];
  Vec3<T> f;
  for (std::int64_t p = s.offsets[k] + first; p < s.offsets[k + 1]; p += stride) {
    const std::int32_t i = s.indices[p];
    const Vec3<T> xki = s.rest[i] - xk;
    const T w = mlsKernelWeight(norm2(xki), s.support);
    f += ((mk + s.stress_moment[i]) * xki) * w;
  }
  return f;
}

template <typename T>
INC_HD Vec3<T> mlsElasticForce(const MlsView<T>& s, std::int64_t k) {
  const Mat3<T> mk = s.stress_moment[k];
  if (s.pair_force) {
    Mat3<T> a[2];
    for (std::int64_t p = s.offsets[k], q = 0; p < s.offsets[k + 1]; ++p, q ^= 1) {
      const Mat3<T>& mi = s.stress_moment[s.indices[p]];
      const Vec3<T> wx = s.pair_force[p];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) a[q].m[r][c] += mi.m[r][c] * wx[c];
    }
    a[0] += a[1];
    return mlsForceFromPairSum(mk, s.weighted_sum[k], a[0]);
  }
  return mlsForcePairSum(s, k, 0, 1);
}

// Particle k's force from its coupling group (it has one).
template <typename T>
INC_HD Vec3<T> mlsCouplingShare(const MlsView<T>& s, std::int64_t k) {
  const std::int32_t g = s.coupling_group[k];
  return couplingMemberForce(s.coupling_force[g], s.coupling_torque, s.coupling_centroid, s.rest[k], g);
}

// Pass 2 at particle k: gather the force (plus its coupling group's share, eq. 12), then the second half kick
// (free particles only). The stored force is what the next drift's first half kick uses.
template <typename T>
INC_HD void mlsForceAt(const MlsView<T>& s, std::int64_t k, Vec3<T> f, T half_dt, bool kick) {
  if (s.elastic_force) s.elastic_force[k] = f;
  if (s.coupling_group && s.coupling_group[k] >= 0) f += mlsCouplingShare(s, k);
  s.force[k] = f;
  if (kick && s.kind[k] == kMlsFree)
    s.velocity[k] = mlsHalfKick(s.velocity[k], f, s.mass[k], s.gravity, half_dt, s.coeffs.damping);
}

template <typename T>
INC_HD void mlsForcePass(const MlsView<T>& s, std::int64_t k, T half_dt, bool kick) {
  mlsForceAt(s, k, mlsElasticForce(s, k), half_dt, kick);
}

// The force at particle k after the coupling forces changed (new anchors) at an unchanged displacement: the
// elastic part the last force pass stored plus the new share, the same sum mlsForcePass forms (no kick).
template <typename T>
INC_HD void mlsCouplingRefresh(const MlsView<T>& s, std::int64_t k) {
  Vec3<T> f = s.elastic_force[k];
  if (s.coupling_group && s.coupling_group[k] >= 0) f += mlsCouplingShare(s, k);
  s.force[k] = f;
}

// First half kick and drift at particle k, using the force of the current displacement. Fixed particles
// keep their displacement and have zero velocity; prescribed ones move on towards their target.
template <typename T>
INC_HD void mlsDriftPass(const MlsView<T>& s, std::int64_t k, T dt, int remaining_substeps) {
  const std::uint8_t kind = s.kind[k];
  if (kind == kMlsFree) {
    const Vec3<T> v = mlsHalfKick(s.velocity[k], s.force[k], s.mass[k], s.gravity, T(0.5) * dt, s.coeffs.damping);
    s.velocity[k] = v;
    s.displacement[k] += v * dt;
    if (s.blade && s.blade->radius > T(0))
      mlsBladeContactAt(*s.blade, s.rest[k], s.displacement[k], s.velocity[k], remaining_substeps);
    if (s.statics) mlsStaticContactAt(*s.statics, s.rest[k], s.displacement[k], s.velocity[k], dt);
  } else if (kind == kMlsPrescribed) {
    mlsPrescribedStep(s.displacement[k], s.velocity[k], s.target[k], dt, remaining_substeps);
  } else {
    s.velocity[k] = Vec3<T>();
  }
}

// The stiffening factor at particle i at the current displacement (mlsStiffeningOf of its gradient).
template <typename T>
INC_HD T mlsStiffening(const MlsView<T>& s, std::int64_t i) {
  return mlsStiffeningOf(mlsDisplacementGradient(s, i), s.coeffs);
}

// Per-particle terms of the frame reductions (energies in J, squared displacement in m^2).
template <typename T>
INC_HD T mlsKineticEnergy(const MlsView<T>& s, std::int64_t k) {
  return T(0.5) * s.mass[k] * norm2(s.velocity[k]);
}
template <typename T>
INC_HD T mlsGravityEnergy(const MlsView<T>& s, std::int64_t k) {
  return -s.mass[k] * dot(s.gravity, s.displacement[k]);
}
template <typename T>
INC_HD bool mlsParticleFinite(const MlsView<T>& s, std::int64_t k) {
  return isFinite(s.displacement[k]) && isFinite(s.velocity[k]) && isFinite(s.force[k]) && std::isfinite(s.energy[k]);
}

}  // namespace inc
