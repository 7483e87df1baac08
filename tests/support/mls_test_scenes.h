// Small MLS test bodies (lattice blocks and beams) and helpers shared by the MLS unit and GPU tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "host/assembly/particle_sampling.h"
#include "model/mls_model.h"

namespace inc::mls_test {

// A block of nx * ny * nz lattice particles of spacing s centred at `center` (m), optional jitter.
inline MlsBuildInput blockInput(int nx, int ny, int nz, double s, double jitter = 0.0, Vec3d center = {0, 0, 0}) {
  MlsBuildInput in;
  in.rest_positions = sampleBox(center, Vec3d(nx * s, ny * s, nz * s), LatticeSpec{s, jitter, 7});
  in.spacing = s;
  in.material.youngs_modulus_pa = 1.0e4;
  in.material.poisson_ratio = 0.3;
  in.material.density_kg_m3 = 1000.0;
  in.material.damping_per_s = 0.0;
  in.material.volume_preservation = false;
  in.gravity = Vec3d(0, 0, 0);
  in.source = "<test block>";
  return in;
}

// Rotation about a unit axis by angle (rad), Rodrigues.
inline Mat3d rotation(Vec3d axis, double angle) {
  axis = axis * (1.0 / norm(axis));
  const double c = std::cos(angle), s = std::sin(angle);
  Mat3d k = Mat3d::fromRows({0, -axis.z, axis.y}, {axis.z, 0, -axis.x}, {-axis.y, axis.x, 0});
  return Mat3d::identity() + k * s + (k * k) * (1.0 - c);
}

// Deterministic pseudo-random number in [-1, 1) from an integer (for displacement fields in tests).
inline double hashSigned(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  x ^= x >> 31;
  return double(x >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

// Largest entry-wise magnitude of a list of vectors.
inline double maxNorm(const std::vector<Vec3d>& v) {
  double m = 0;
  for (const auto& x : v) m = std::max(m, norm(x));
  return m;
}

}  // namespace inc::mls_test
