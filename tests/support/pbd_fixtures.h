// Shared PBD test models (hanging chain, lattice beam/block) and a frame loop, for the CPU and GPU PBD tests.
#pragma once

#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include "host/assembly/pbd_builders.h"
#include "model/pbd_model.h"

namespace inc::test {

// N particles of mass m hanging along -z from particle 0 (fixed at the origin), rest spacing d, one distance
// constraint per link with compliance alpha (m/N) and PBD stiffness k.
template <typename T>
PbdModel<T> makeHangingChain(int n, double d, double m, double alpha, double k = 1.0) {
  PbdModel<T> model;
  for (int i = 0; i < n; ++i) {
    model.rest_positions.push_back(Vec3<T>(T(0), T(0), T(-i * d)));
    model.masses.push_back(T(m));
    model.inv_mass.push_back(i == 0 ? T(0) : T(1.0 / m));
    model.rest_radii.push_back(T(0));
  }
  PbdConstraintBlock<T> b;
  b.kind = PbdConstraintKind::Distance;
  b.stiffness = T(k);
  for (int i = 1; i < n; ++i) {
    b.ids.push_back(i - 1);
    b.ids.push_back(i);
    b.offsets.push_back(std::int32_t(b.ids.size()));
    b.rest.push_back(T(d));
    b.compliance.push_back(T(alpha));
  }
  model.blocks.push_back(std::move(b));
  model.overlap_offsets.assign(std::size_t(n) + 1, 0);
  finalizePbdModel(model);
  return model;
}

// One free sphere (radius 1 cm, 10 g) at the origin with the given static planes, finalised without a colouring:
// the contact and friction tests' body.
inline PbdModel<double> makeFreeSphere(std::vector<pbd::PlaneCollider<double>> planes = {}) {
  PbdModel<double> m;
  m.rest_positions = {Vec3d(0, 0, 0)};
  m.masses = {0.01};
  m.inv_mass = {100.0};
  m.rest_radii = {0.01};
  m.planes = std::move(planes);
  finalizePbdModel(m, false);
  return m;
}

// Analytic static sag of that chain: link k (from the top, k = 1..n-1) carries T_k = (n - k) m g and
// stretches by alpha T_k; returns the tip's downward displacement alpha m g n (n - 1) / 2.
inline double chainTipSag(int n, double m, double alpha, double g) { return alpha * m * g * n * (n - 1) / 2.0; }

// Lattice beam [0, L] x [0, W] x [0, H] of metaballs, clamped at x = 0 (spheres with x < spacing/2 fixed).
template <typename T>
PbdModel<T> makeLatticeBeam(double length, double width, double height, double spacing, double youngs,
                            bool clamp = true, int volume_samples = 0) {
  const MetaballModel mb = makeLatticeMetaballs(Vec3d(0, 0, 0), Vec3d(length, width, height), spacing, 0.75, 1000.0);
  MetaballPbdOptions opt;
  opt.youngs_modulus_pa = youngs;
  opt.volume_samples = volume_samples;
  if (clamp) {
    FixedRegion r;
    r.min = Vec3d(-1, -1, -1);
    r.max = Vec3d(0.5 * spacing, width + 1, height + 1);
    opt.fixed.push_back(r);
  }
  return buildMetaballPbdModel<T>(mb, opt);
}

// Mean downward displacement (m) of the particles whose rest x lies beyond `tip_x` (a beam's free end).
template <typename T>
double meanTipSag(const PbdModel<T>& m, const PbdState<T>& s, double tip_x) {
  double tip = 0;
  int cnt = 0;
  for (std::size_t i = 0; i < m.size(); ++i)
    if (double(m.rest_positions[i].x) > tip_x) {
      tip += double(m.rest_positions[i].z - s.positions[i].z);
      ++cnt;
    }
  return cnt > 0 ? tip / cnt : 0.0;
}

template <typename T>
PbdFrameStats runFrames(PbdBackend<T>& backend, const PbdStepParams<T>& p, int frames,
                        const PbdFrameInput<T>& in = PbdFrameInput<T>()) {
  PbdFrameStats st;
  for (int f = 0; f < frames; ++f) st = backend.advanceFrame(p, in);
  return st;
}

}  // namespace inc::test
