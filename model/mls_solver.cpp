// The MLS solver's shared host-side parts: positions in double, the coupling groups' checks, frames and stable step.
#include "model/mls_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Dense>

#include "physics/cut_coupling.h"

namespace inc {

void MlsSolver::positions(std::vector<Vec3d>& out) const {
  displacements(out);
  const std::vector<Vec3d> rest = restPositions();
  for (std::size_t i = 0; i < out.size(); ++i) out[i] += rest[i];
}

void validateMlsCouplingGroups(const MlsCouplingGroups& g, std::size_t particles) {
  const char* f = "coupling";
  const std::size_t n = g.size();
  if (g.member_offsets.size() != n + 1 || g.spring_offsets.size() != n + 1)
    throw InputError(f, "offsets", "need one member and one spring offset per group plus one");
  if (g.member_offsets.front() != 0 || std::size_t(g.member_offsets.back()) != g.members.size())
    throw InputError(f, "member_offsets", "must start at 0 and end at the member count");
  if (g.spring_offsets.front() != 0 || std::size_t(g.spring_offsets.back()) != g.springs() ||
      g.stiffnesses.size() != g.springs())
    throw InputError(f, "spring_offsets", "must start at 0 and end at the spring count (one stiffness per spring)");
  std::vector<char> seen(particles, 0);
  for (std::size_t k = 0; k < n; ++k) {
    if (!(g.member_offsets[k + 1] > g.member_offsets[k]))
      throw InputError(f, "members", "group " + std::to_string(k) + " has no member");
    if (g.spring_offsets[k + 1] < g.spring_offsets[k]) throw InputError(f, "spring_offsets", "must not decrease");
    if (!isFinite(g.rest_centres[k])) throw InputError(f, "rest_centres", "not finite");
  }
  for (const std::int32_t i : g.members) {
    if (i < 0 || std::size_t(i) >= particles) throw InputError(f, "members", "particle index out of range");
    if (seen[std::size_t(i)]) throw InputError(f, "members", "particle " + std::to_string(i) + " is in two groups");
    seen[std::size_t(i)] = 1;
  }
  for (std::size_t s = 0; s < g.springs(); ++s) {
    if (!(std::isfinite(g.rest_lengths[s]) && g.rest_lengths[s] > 0))
      throw InputError(f, "rest_lengths", "must be finite and > 0");
    if (!(std::isfinite(g.stiffnesses[s]) && g.stiffnesses[s] >= 0))
      throw InputError(f, "stiffnesses", "must be finite and >= 0");
  }
}

MlsCouplingFrames mlsCouplingFrames(const MlsCouplingGroups& g, const std::vector<Vec3d>& rest) {
  MlsCouplingFrames fr;
  fr.centroid.resize(g.size());
  fr.gram.resize(g.size());
  fr.inertia_inverse.resize(g.size());
  fr.min_inertia.assign(g.size(), 0.0);
  for (std::size_t k = 0; k < g.size(); ++k) {
    const std::int32_t b = g.member_offsets[k], e = g.member_offsets[k + 1];
    Vec3d c;
    for (std::int32_t p = b; p < e; ++p) c += rest[std::size_t(g.members[std::size_t(p)])];
    c *= 1.0 / double(e - b);
    Mat3d q2;
    for (std::int32_t p = b; p < e; ++p) {
      const Vec3d q = rest[std::size_t(g.members[std::size_t(p)])] - c;
      q2 += outer(q, q);
    }
    const Mat3d j = Mat3d::diag(trace(q2)) - q2;  // sum (|q|^2 I - q q^T)
    fr.centroid[k] = c;
    fr.gram[k] = q2;
    if (e - b < 4) continue;
    Eigen::Matrix3d jm;
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 3; ++col) jm(r, col) = j.m[r][col];
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(jm);
    const Eigen::Vector3d lam = eig.eigenvalues();  // ascending
    if (!(lam(0) > kCouplingMinInertiaRatio * lam.sum())) continue;
    const Eigen::Matrix3d inv = eig.eigenvectors() * lam.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 3; ++col) fr.inertia_inverse[k].m[r][col] = inv(r, col);
    fr.min_inertia[k] = lam(0);
  }
  return fr;
}

double mlsCouplingStableStep(const MlsCouplingGroups& g, const std::vector<double>& mass, const MlsCouplingFrames* fr) {
  double omega = 0.0;
  for (std::size_t k = 0; k < g.size(); ++k) {
    double m = 0.0, m_min = std::numeric_limits<double>::infinity();
    for (std::int32_t p = g.member_offsets[k]; p < g.member_offsets[k + 1]; ++p) {
      const double mi = mass[std::size_t(g.members[std::size_t(p)])];
      m += mi;
      m_min = std::min(m_min, mi);
    }
    omega = std::max(omega, couplingGroupOmega(g.stiffnesses.data(), g.spring_offsets[k], g.spring_offsets[k + 1], m));
    if (fr && fr->min_inertia[k] > 0.0 && m_min > 0.0) {
      double ksum = 0.0;
      for (std::int32_t s = g.spring_offsets[k]; s < g.spring_offsets[k + 1]; ++s)
        ksum += g.stiffnesses[std::size_t(s)];
      const Vec3d arm = g.rest_centres[k] - fr->centroid[k];
      omega = std::max(omega, std::sqrt(ksum * dot(arm, arm) / (m_min * fr->min_inertia[k])));
    }
  }
  return omega > 0.0 ? 2.0 / omega : std::numeric_limits<double>::infinity();
}

}  // namespace inc
