// Builds an MLS model from sampled particles: validation, rest neighbourhoods, densities, volumes, A_i^{-1}.
#include "host/assembly/mls_model_build.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/parallel.h"
#include "cpu_fallback/neighbor_search_cpu.h"
#include "host/compiled/material_checks.h"
#include "model/input_error.h"

namespace inc {

namespace {

bool finite(double x) { return std::isfinite(x); }

void require(bool ok, const MlsBuildInput& in, const std::string& key, const std::string& reason) {
  if (!ok) throw InputError(in.source, key, reason);
}

}  // namespace

void validateMlsBuildInput(const MlsBuildInput& in) {
  const std::size_t n = in.rest_positions.size();
  require(n > 0, in, "geometry", "no particles: the geometry sampled to an empty set");
  require(n < std::size_t(std::numeric_limits<std::int32_t>::max()), in, "geometry", "more than 2^31 particles");
  require(finite(in.spacing) && in.spacing > 0, in, "geometry.spacing_m", "must be a positive number");
  require(finite(in.support_factor) && in.support_factor >= 1.2 && in.support_factor <= 4.0, in, "mls.support_factor",
          "must lie in [1.2, 4] (h = factor * spacing)");
  require(finite(in.condition_limit) && in.condition_limit > 1.0, in, "mls.condition_limit", "must be > 1");
  const MlsMaterial& m = in.material;
  validateMaterial(m, in.source);  // the scene's own check: an MLS build also comes from tests and tools
  require(finite(m.volume_stiffness) && m.volume_stiffness >= 0, in, "mls.volume_stiffness", "must be >= 0");
  require(finite(in.safety) && in.safety > 0 && in.safety <= 1, in, "solver.safety", "must lie in (0, 1]");
  require(finite(in.gravity.x) && finite(in.gravity.y) && finite(in.gravity.z), in, "solver.gravity_m_s2",
          "must be finite");
  require(in.masses.empty() || in.masses.size() == n, in, "masses", "one mass per particle");
  require(in.kinds.empty() || in.kinds.size() == n, in, "kinds", "one kind per particle");
  // Per-particle checks test first and build the message only on failure (a message per particle cost more
  // than the whole model build).
  for (std::size_t i = 0; i < in.masses.size(); ++i)
    if (!(finite(in.masses[i]) && in.masses[i] > 0))
      require(false, in, "masses", "particle " + std::to_string(i) + ": mass must be > 0");
  for (std::size_t i = 0; i < in.kinds.size(); ++i)
    if (!(in.kinds[i] <= kMlsPrescribed))
      require(false, in, "kinds", "particle " + std::to_string(i) + ": unknown kind");
  for (std::size_t i = 0; i < n; ++i)
    if (!isFinite(in.rest_positions[i]))
      require(false, in, "geometry", "particle " + std::to_string(i) + ": non-finite position");
}

MlsCoefficients<double> mlsCoefficients(const MlsMaterial& m) {
  return mlsSplitCoefficients(m.youngs_modulus_pa, m.poisson_ratio, m.volume_preservation, m.volume_stiffness,
                              m.damping_per_s);
}

template <typename T>
NeighborLists buildMlsRestNeighbors(const std::vector<Vec3<T>>& rest, T radius) {
  // Cells of edge h: each query visits the 27 cells around it. Closed ball, distance2Exact, ascending.
  const cpu::GridNeighborSearch<T> grid(rest, radius);
  return grid.querySelf(radius);
}

namespace {

// Rest positions relative to their centroid: float32 rest differences X_j - X_i then keep ~7 digits relative to
// the spacing instead of relative to the distance from the scene origin.
template <typename T>
void setRestAboutCentroid(MlsModel<T>& md, const std::vector<Vec3d>& positions) {
  const std::size_t n = positions.size();
  Vec3d c;
  for (const auto& p : positions) c += p;
  md.origin = c * (1.0 / double(n));
  md.rest.resize(n);
  for (std::size_t i = 0; i < n; ++i) md.rest[i] = Vec3<T>(positions[i] - md.origin);
}

// The caller's rest neighbourhoods, checked; without them, the closed ball of radius h from the grid search.
template <typename T>
NeighborLists restNeighbors(const MlsBuildInput& in, const std::vector<Vec3<T>>& rest, T h) {
  if (in.neighbors.offsets.empty()) return buildMlsRestNeighbors(rest, h);
  const std::size_t n = rest.size();
  const NeighborLists& l = in.neighbors;
  require(l.offsets.size() == n + 1 && l.offsets.front() == 0 && std::size_t(l.offsets.back()) == l.indices.size(), in,
          "neighbors", "CSR offsets must hold one entry per particle plus one, from 0 to the index count");
  for (std::size_t i = 0; i < n; ++i)
    for (std::int64_t p = l.offsets[i]; p < l.offsets[i + 1]; ++p) {
      const std::int32_t j = l.indices[std::size_t(p)];
      if (!(j >= 0 && std::size_t(j) < n && std::size_t(j) != i))
        require(false, in, "neighbors", "particle " + std::to_string(i) + ": neighbour index out of range or itself");
    }
  return l;
}

// Per-particle rest quantities kept in double until they are stored in precision T.
struct RestQuantities {
  std::vector<double> mass, density, volume, condition;
};

// Densities, volumes and A_i^{-1} in double from the (precision-T) rest positions; the weights use the
// precision-T support so that they match what the passes evaluate. Fills md.moment_inverse and md.degeneracy.
template <typename T>
RestQuantities restQuantities(MlsModel<T>& md, const MlsBuildInput& in) {
  const std::size_t n = md.rest.size();
  const double rho0 = in.material.density_kg_m3;
  const double spacing = in.spacing;
  RestQuantities q;
  q.mass.resize(n);
  for (std::size_t i = 0; i < n; ++i) q.mass[i] = in.masses.empty() ? rho0 * spacing * spacing * spacing : in.masses[i];
  q.density.resize(n);
  q.volume.resize(n);
  q.condition.resize(n);
  md.moment_inverse.resize(n);
  md.degeneracy.resize(n);
  const double hd = double(md.support);
  const double w0 = mlsKernelWeight(0.0, hd);
  cpu::parallelFor(std::int64_t(n), [&](std::int64_t i) {
    const Vec3d xi(md.rest[std::size_t(i)]);
    double rho = q.mass[std::size_t(i)] * w0, nominal = q.mass[std::size_t(i)] / rho0 * w0;
    Mat3d a;
    int count = 0;
    for (std::int64_t p = md.neighbors.offsets[std::size_t(i)]; p < md.neighbors.offsets[std::size_t(i) + 1]; ++p) {
      const std::int32_t j = md.neighbors.indices[std::size_t(p)];
      const Vec3d xij = Vec3d(md.rest[std::size_t(j)]) - xi;
      const double w = mlsKernelWeight(norm2(xij), hd);
      if (w > 0) ++count;
      rho += q.mass[std::size_t(j)] * w;
      nominal += q.mass[std::size_t(j)] / rho0 * w;
      accumulateMomentMatrix(a, xij, w);  // eq. 6
    }
    q.density[std::size_t(i)] = in.volume_estimate == MlsVolumeEstimate::ShepardKernelSum ? rho / nominal : rho;
    q.volume[std::size_t(i)] = q.mass[std::size_t(i)] / q.density[std::size_t(i)];
    const MomentInverse<double> inv = regularisedMomentInverse(a, count, in.condition_limit);
    md.moment_inverse[std::size_t(i)] = Mat3<T>(inv.inverse);
    md.degeneracy[std::size_t(i)] = inv.flags;
    q.condition[std::size_t(i)] = inv.condition;
  });
  return q;
}

template <typename T>
void storeRestQuantities(MlsModel<T>& md, const RestQuantities& q) {
  const std::size_t n = q.mass.size();
  md.mass.resize(n);
  md.density.resize(n);
  md.volume.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    md.mass[i] = T(q.mass[i]);
    md.density[i] = T(q.density[i]);
    md.volume[i] = T(q.volume[i]);
  }
}

// Counts of degenerate and constrained particles, neighbourhood sizes, density range and totals.
template <typename T>
MlsModelStats restStats(const MlsModel<T>& md, const RestQuantities& q) {
  const std::size_t n = q.mass.size();
  MlsModelStats s;
  s.particles = std::int64_t(n);
  s.min_neighbors = std::numeric_limits<std::int64_t>::max();
  s.min_density = std::numeric_limits<double>::infinity();
  s.max_density = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t f = md.degeneracy[i];
    s.isolated += (f & kMlsIsolated) ? 1 : 0;
    s.few_neighbors += (f & kMlsFewNeighbors) ? 1 : 0;
    s.coplanar += (f & kMlsCoplanar) ? 1 : 0;
    s.collinear += (f & kMlsCollinear) ? 1 : 0;
    s.ill_conditioned += (f & kMlsIllConditioned) ? 1 : 0;
    s.regularised += f != kMlsRegular ? 1 : 0;
    s.fixed += md.kind[i] == kMlsFixed ? 1 : 0;
    s.prescribed += md.kind[i] == kMlsPrescribed ? 1 : 0;
    const std::int64_t cnt = std::int64_t(md.neighbors.count(i));
    s.min_neighbors = std::min(s.min_neighbors, cnt);
    s.max_neighbors = std::max(s.max_neighbors, cnt);
    s.mean_neighbors += double(cnt);
    if (std::isfinite(q.condition[i])) s.max_condition = std::max(s.max_condition, q.condition[i]);
    s.min_density = std::min(s.min_density, q.density[i]);
    s.max_density = std::max(s.max_density, q.density[i]);
    s.total_mass += q.mass[i];
    s.total_volume += q.volume[i];
  }
  s.mean_neighbors /= double(n);
  return s;
}

}  // namespace

template <typename T>
MlsModel<T> buildMlsModel(const MlsBuildInput& in) {
  validateMlsBuildInput(in);
  const std::size_t n = in.rest_positions.size();
  MlsModel<T> md;
  md.source = in.source;
  md.material = in.material;
  md.safety = in.safety;
  setRestAboutCentroid(md, in.rest_positions);
  md.spacing = T(in.spacing);
  md.support = T(in.support_factor * in.spacing);
  md.neighbors = restNeighbors(in, md.rest, md.support);
  md.kind = in.kinds.empty() ? std::vector<std::uint8_t>(n, kMlsFree) : in.kinds;

  const RestQuantities q = restQuantities(md, in);
  storeRestQuantities(md, q);
  md.stats = restStats(md, q);

  const MlsCoefficients<double> cd = mlsCoefficients(in.material);
  md.coeffs.mu = T(cd.mu);
  md.coeffs.lambda = T(cd.lambda);
  md.coeffs.k_volume = T(cd.k_volume);
  md.coeffs.damping = T(cd.damping);
  md.gravity = Vec3<T>(in.gravity);
  // The lightest particle (lowest rho_i) sets the fastest wave.
  md.stats.stable_dt = mlsStableTimeStep(cd.mu, cd.lambda, cd.k_volume, md.stats.min_density, in.spacing);
  return md;
}

template NeighborLists buildMlsRestNeighbors<float>(const std::vector<Vec3f>&, float);
template NeighborLists buildMlsRestNeighbors<double>(const std::vector<Vec3d>&, double);
template MlsModel<float> buildMlsModel<float>(const MlsBuildInput&);
template MlsModel<double> buildMlsModel<double>(const MlsBuildInput&);

}  // namespace inc
