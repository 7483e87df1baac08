// Chebyshev-accelerated Jacobi PBD: the same equilibrium as the plain iteration, reached in fewer iterations; no
// blow-up at any iteration count or at extreme stiffness and step; out-of-range estimates refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "cpu_fallback/pbd_solver_cpu.h"
#include "tests/support/pbd_drop_check.h"
#include "tests/support/pbd_fixtures.h"

using namespace inc;

namespace {

// Settled tip deflection (downward, m) of a clamped 10 cm metaball lattice beam (1 cm spheres, E = 2e4 Pa) under
// gravity after 150 frames of damped sagging.
double beamTipDeflection(PbdSolverKind solver, int iterations, double rho) {
  const double L = 0.1, W = 0.02, H = 0.02, s = 0.01;
  const PbdModel<double> m = test::makeLatticeBeam<double>(L, W, H, s, 2.0e4);
  auto be = cpu::makePbdCpuBackend<double>();
  be->setModel(m);
  PbdStepParams<double> p;
  p.solver = solver;
  p.iterations = iterations;
  p.substeps = 4;
  p.chebyshev_rho = rho;
  p.damping = 10.0;
  p.volume_preservation = false;
  const PbdFrameStats st = test::runFrames(*be, p, 150);
  EXPECT_TRUE(st.finite);
  PbdState<double> x;
  be->getState(x);
  return test::meanTipSag(m, x, L - 0.5 * s);
}

}  // namespace

// The accelerated iteration has the plain one's fixed point: with enough iterations it reaches the Gauss-Seidel
// equilibrium. Along the way it needs half the iterations of plain Jacobi for the same error on this long beam
// (measured: 10 accelerated iterations 0.0663 m against 20 plain 0.0695 m, the equilibrium 0.0336 m; 20 against
// 40: 0.0533 / 0.0559 m). On the liver-sized block (bench_pbd) 10 iterations: 25.6 % -> 14.3 % error.
TEST(PbdChebyshev, SameBeamEquilibriumInHalfTheIterations) {
  using S = PbdSolverKind;
  const double rho = pbd::kChebyshevMaxRho;
  const double ref = beamTipDeflection(S::GaussSeidel, 80, 0.0);
  const double ja20 = beamTipDeflection(S::Jacobi, 20, 0.0), ch10 = beamTipDeflection(S::Jacobi, 10, rho);
  const double ja40 = beamTipDeflection(S::Jacobi, 40, 0.0), ch20 = beamTipDeflection(S::Jacobi, 20, rho);
  const double ch160 = beamTipDeflection(S::Jacobi, 160, rho);
  std::printf(
      "beam tip: Gauss-Seidel 80 it %.6g m; Jacobi 20 / 40 it %.6g / %.6g; Chebyshev %.2f 10 / 20 / 160 it "
      "%.6g / %.6g / %.6g\n",
      ref, ja20, ja40, rho, ch10, ch20, ch160);
  ASSERT_GT(ref, 1e-2);              // it does bend (3.4 cm on 10 cm)
  EXPECT_GT(ja20 - ref, 0.5 * ref);  // plain Jacobi is far from converged at these counts (sags too much) ...
  EXPECT_LT(std::fabs(ch10 - ref), std::fabs(ja20 - ref));  // ... the accelerated one as near in half the iterations
  EXPECT_LT(std::fabs(ch20 - ref), std::fabs(ja40 - ref));
  EXPECT_NEAR(ch160, ref, 0.02 * ref);  // and converges to the same equilibrium
}

// The largest accepted estimate (0.9) at every iteration count from 1 to 12 at every iteration count from 1 to 12, with
// an infinitely stiff and a nearly free material, at 60 Hz and at a 0.1 s frame in one substep: positions stay finite,
// above the ground, and the kinetic energy below the potential energy the block started with (the test of PbdSolver's
// NoExplosionAtExtremeComplianceAndTimeStep, which the plain solvers pass).
TEST(PbdChebyshev, NoBlowUpAtAnyIterationCountOrExtremeMaterial) {
  for (double youngs : {1.0e12, 2.0e4, 1.0e-3})
    for (double frame_dt : {0.1, 1.0 / 60.0})
      for (int iterations = 1; iterations <= 12; ++iterations) {
        PbdStepParams<double> p;
        p.frame_dt = frame_dt;
        p.substeps = 1;
        p.iterations = iterations;
        p.chebyshev_rho = pbd::kChebyshevMaxRho;
        test::expectDropStaysBounded(
            youngs, p,
            "E " + std::to_string(youngs) + " dt " + std::to_string(frame_dt) + " it " + std::to_string(iterations));
      }
}

// rho outside [0, 0.9] (or not a number) and rho with Gauss-Seidel are InputErrors naming chebyshev_rho; 0 and
// 0.9 are accepted.
TEST(PbdChebyshev, OutOfRangeEstimateOrGaussSeidelIsRefused) {
  auto be = cpu::makePbdCpuBackend<double>();
  be->setModel(test::makeHangingChain<double>(4, 0.1, 0.01, 0.0));
  PbdStepParams<double> p;
  for (double rho : {-0.1, 0.901, 1.0, std::numeric_limits<double>::quiet_NaN()}) {
    p.chebyshev_rho = rho;
    try {
      be->advanceFrame(p, PbdFrameInput<double>());
      ADD_FAILURE() << "rho " << rho << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), "chebyshev_rho");
    }
  }
  p.chebyshev_rho = 0.5;
  p.solver = PbdSolverKind::GaussSeidel;
  EXPECT_THROW(be->advanceFrame(p, PbdFrameInput<double>()), InputError);
  p.solver = PbdSolverKind::Jacobi;
  for (double rho : {0.0, 0.9}) {
    p.chebyshev_rho = rho;
    EXPECT_NO_THROW(be->advanceFrame(p, PbdFrameInput<double>()));
  }
}
