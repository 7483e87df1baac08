// The MLS solid's rest configuration (MlsModel<T>) and state (MlsState<T>), and how a model is built.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "model/material.h"
#include "model/neighbor_lists.h"
#include "physics/mls_elasticity.h"
#include "physics/mls_integrate.h"
#include "physics/mls_kernel.h"
#include "physics/mls_passes.h"
#include "physics/vec3.h"

namespace inc {

// The material of an MLS body: the scene's Material (model/material.h) and the volume penalty only MLS has.
struct MlsMaterial : Material {
  bool volume_preservation = true;  // penalty k_v/2 (det F - 1)^2
  double volume_stiffness = 1.0;    // k_v as a multiple of the bulk modulus, >= 0
};

// How the rest volume v_i = m_i / rho_i gets its density rho_i.
enum class MlsVolumeEstimate {
  // rho_i = sum_j m_j w_ij / sum_j (m_j / rho_0) w_ij: the kernel sum with Shepard normalisation, which
  // removes the free-surface deficit of the plain sum (for a uniform body it returns rho_0, so volumes
  // tile the body and sum to its volume). Default: see docs/mls.md.
  ShepardKernelSum,
  // rho_i = sum_j m_j w_ij (Mueller et al. 2004): underestimates rho by up to ~50% within h of a free
  // surface, so surface particles get too much volume and the body is too stiff in bending.
  KernelSum,
};

// Everything needed to build a model, in double and SI units, independent of backend and precision.
struct MlsBuildInput {
  std::vector<Vec3d> rest_positions;  // m
  std::vector<double> masses;         // kg per particle; empty: density * spacing^3 each
  std::vector<std::uint8_t> kinds;    // MlsParticleKind per particle; empty: all free
  double spacing = 0.005;             // m, sample spacing
  double support_factor = 2.0;        // h = support_factor * spacing
  double condition_limit = 1.0e6;     // cond(A_i) above this gets a regularised inverse; > 1
  MlsVolumeEstimate volume_estimate = MlsVolumeEstimate::ShepardKernelSum;
  MlsMaterial material;
  Vec3d gravity{0, 0, -9.81};    // m/s^2
  double safety = 0.5;           // fraction of the stable step used when substepping, (0, 1]
  std::string source = "<mls>";  // for error messages (scene file)
  // Optional rest neighbourhoods chosen by the caller (a cut's visibility-filtered supports): CSR over the
  // particles, symmetric, no self pairs, each pair within the support h. Empty (no offsets): the closed ball of
  // radius h found by the grid search.
  NeighborLists neighbors;
};

// Facts about the rest configuration, computed once per build (reported in metrics).
struct MlsModelStats {
  std::int64_t particles = 0;
  std::int64_t isolated = 0, few_neighbors = 0, coplanar = 0, collinear = 0, ill_conditioned = 0;
  std::int64_t regularised = 0;  // any of the above: got a ridge or a zero inverse
  std::int64_t fixed = 0, prescribed = 0;
  std::int64_t min_neighbors = 0, max_neighbors = 0;
  double mean_neighbors = 0.0;
  double max_condition = 0.0;                   // largest finite cond(A_i)
  double min_density = 0.0, max_density = 0.0;  // kg/m^3
  double total_mass = 0.0;                      // kg
  double total_volume = 0.0;                    // m^3
  double stable_dt = 0.0;                       // s, safety 1
};

template <typename T>
struct MlsModel {
  Vec3d origin;                          // rest positions are stored relative to this (m, double)
  std::vector<Vec3<T>> rest;             // X_i - origin (m)
  std::vector<T> mass;                   // kg
  std::vector<T> density;                // rho_i (kg/m^3)
  std::vector<T> volume;                 // v_i = m_i / rho_i (m^3)
  std::vector<Mat3<T>> moment_inverse;   // regularised A_i^{-1} (eq. 6), m
  std::vector<std::uint8_t> degeneracy;  // MlsDegeneracy flags
  std::vector<std::uint8_t> kind;        // MlsParticleKind
  NeighborLists neighbors;               // rest neighbourhoods, closed ball of radius h, symmetric
  T spacing = T(0), support = T(0);      // m
  MlsCoefficients<T> coeffs;
  Vec3<T> gravity;  // m/s^2
  MlsMaterial material;
  double safety = 0.5;
  MlsModelStats stats;
  std::string source;
  std::size_t size() const { return rest.size(); }
  // Resident bytes of the model arrays (host or device alike).
  std::size_t bytes() const {
    return rest.size() * (sizeof(Vec3<T>) + 3 * sizeof(T) + sizeof(Mat3<T>) + 2) +
           neighbors.offsets.size() * sizeof(std::int64_t) + neighbors.indices.size() * sizeof(std::int32_t);
  }
};

// Per-particle dynamic state (host copy; the CUDA solver keeps its own resident on the device).
template <typename T>
struct MlsState {
  std::vector<Vec3<T>> displacement;   // u_i (m)
  std::vector<Vec3<T>> velocity;       // m/s
  std::vector<Vec3<T>> force;          // elastic force (N) at the current displacement
  std::vector<Vec3<T>> target;         // prescribed displacement (m), used where kind == prescribed
  std::vector<Mat3<T>> stress_moment;  // pass-1 scratch M_i
  std::vector<T> energy;               // pass-1 scratch v_i psi_i (J)
  void resize(std::size_t n) {
    displacement.assign(n, Vec3<T>());
    velocity.assign(n, Vec3<T>());
    force.assign(n, Vec3<T>());
    target.assign(n, Vec3<T>());
    stress_moment.assign(n, Mat3<T>());
    energy.assign(n, T(0));
  }
  std::size_t bytes() const { return displacement.size() * (4 * sizeof(Vec3<T>) + sizeof(Mat3<T>) + sizeof(T)); }
};

// The views the passes run on, over host vectors (inline: the CPU fallback uses it without host code).
template <typename T>
MlsView<T> makeMlsView(const MlsModel<T>& model, MlsState<T>& state) {
  MlsView<T> v;
  v.n = std::int64_t(model.size());
  v.rest = model.rest.data();
  v.mass = model.mass.data();
  v.volume = model.volume.data();
  v.moment_inverse = model.moment_inverse.data();
  v.kind = model.kind.data();
  v.offsets = model.neighbors.offsets.data();
  v.indices = model.neighbors.indices.data();
  v.support = model.support;
  v.coeffs = model.coeffs;
  v.gravity = model.gravity;
  v.displacement = state.displacement.data();
  v.velocity = state.velocity.data();
  v.force = state.force.data();
  v.target = state.target.data();
  v.stress_moment = state.stress_moment.data();
  v.energy = state.energy.data();
  return v;
}

}  // namespace inc
