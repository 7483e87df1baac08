// The PBD robustness check shared by the solver tests: a metaball block dropped onto a floor stays finite, above it,
// and gains no energy.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "cpu_fallback/pbd_solver_cpu.h"
#include "tests/support/pbd_fixtures.h"

namespace inc::test {

// A 3 x 3 x 5 cm block of 1 cm metaballs (Young's modulus `youngs`, radii fixed), its bottom 2 cm above a floor,
// dropped for 40 frames with `p` (volume preservation off) on the CPU backend: the state stays finite, no sphere
// sinks into the floor (1 um), and the kinetic energy stays below the potential energy the block started with.
// `what` names the case in a failure.
inline void expectDropStaysBounded(double youngs, PbdStepParams<double> p, const std::string& what) {
  const MetaballModel mb = makeLatticeMetaballs(Vec3d(0, 0, 0.02), Vec3d(0.03, 0.03, 0.05), 0.01, 0.75, 1000.0);
  MetaballPbdOptions opt;
  opt.youngs_modulus_pa = youngs;
  opt.volume_samples = 0;  // radii fixed: the floor test uses the radii the contacts saw
  PbdModel<double> m = buildMetaballPbdModel<double>(mb, opt);
  m.planes.push_back(pbd::PlaneCollider<double>());
  double pe = 0;
  for (std::size_t i = 0; i < m.size(); ++i) pe += m.masses[i] * 9.81 * m.rest_positions[i].z;
  auto be = cpu::makePbdCpuBackend<double>();
  be->setModel(m);
  p.volume_preservation = false;
  const PbdFrameStats st = runFrames(*be, p, 40);
  PbdState<double> s;
  be->getState(s);
  ASSERT_TRUE(st.finite) << what;
  double zmin = 1e9, ke = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    zmin = std::min(zmin, s.positions[i].z - s.radii[i]);
    ke += 0.5 * m.masses[i] * norm2(s.velocities[i]);
  }
  EXPECT_GT(zmin, -1e-6) << what;
  EXPECT_LT(ke, pe) << what;
}

}  // namespace inc::test
