// Unit tests of the Tresca tearing math: eq. 6 yield test, strain extrema, seeded fractions, closed-form principal
// stresses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "physics/tearing_tresca.h"

using namespace inc;
using namespace inc::tear;

TEST(TearingTresca, Eq6YieldExactlyAtTau) {
  StrainExtrema<double> e;
  accumulateStrain(e, 0.30, 4);
  accumulateStrain(e, -0.10, 7);
  accumulateStrain(e, 0.05, 9);
  EXPECT_EQ(e.partner_max, 4);
  EXPECT_EQ(e.partner_min, 7);
  // k = 1000 Pa: |300 - (-100)| / 2 = 200 Pa.
  EXPECT_NEAR(trescaShear(1000.0, e.rho_max, e.rho_min), 200.0, 1e-12);
  EXPECT_TRUE(trescaYield(e, 1000.0, 200.0 - 1e-9));
  EXPECT_FALSE(trescaYield(e, 1000.0, 200.0 + 1e-6));
  StrainExtrema<double> one;
  accumulateStrain(one, 5.0, 1);
  EXPECT_FALSE(trescaYield(one, 1000.0, 1.0));  // a single bond has no stress difference
  EXPECT_TRUE(thresholdYield(one, 4.0));
}

TEST(TearingTresca, BondStrainIsRelative) {
  EXPECT_NEAR(bondStrain(Vec3d(0, 0, 0), Vec3d(0, 1.5, 0), 1.0), 0.5, 1e-15);
  EXPECT_NEAR(bondStrain(Vec3d(0, 0, 0), Vec3d(0, 0, 0.02), 0.04), -0.5, 1e-15);
}

TEST(TearingTresca, FractionIsHalfForZeroMinStressAndStaysInRange) {
  EXPECT_NEAR(predictedFraction(100.0, 0.0), 0.5, 1e-15);
  EXPECT_NEAR(predictedFraction(100.0, 50.0), 0.25, 1e-15);
  std::set<std::uint32_t> seen;
  double lo = 1, hi = 0;
  for (std::uint32_t s = 0; s < 2000; ++s) {
    const double u = tearUniform<double>(7, s, s + 1, 3);
    ASSERT_GE(u, -1.0);
    ASSERT_LE(u, 1.0);
    const double t = perturbedFraction(0.5, 0.1, u, 0.05, 0.95);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
    seen.insert(tearHash(7, s, s + 1, 3));
  }
  EXPECT_GE(lo, 0.45);
  EXPECT_LE(hi, 0.55);
  EXPECT_LT(lo, 0.46);  // the range is actually used (2000 draws)
  EXPECT_GT(hi, 0.54);
  EXPECT_EQ(seen.size(), 2000u);
  // Float and double draw the same u (24-bit mantissa is exact in both).
  EXPECT_EQ(double(tearUniform<float>(3, 10, 11, 12)), tearUniform<double>(3, 10, 11, 12));
  EXPECT_NE(tearHash(1, 2, 3, 4), tearHash(2, 2, 3, 4));
}

TEST(TearingTresca, ClosedFormEigenvaluesMatchRotatedDiagonal) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> d(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    double ev[3] = {d(rng) * 100, d(rng) * 100, d(rng) * 100};
    if (trial % 10 == 0) ev[1] = ev[0];  // repeated eigenvalue
    // random rotation from a random unit quaternion
    double q[4] = {d(rng), d(rng), d(rng), d(rng)};
    const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (double& c : q) c /= qn;
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    Mat3d r = Mat3d::fromRows(Vec3d(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
                              Vec3d(2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
                              Vec3d(2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)));
    Mat3d dg;
    for (int k = 0; k < 3; ++k) dg(k, k) = ev[k];
    const Mat3d a = r * dg * transpose(r);
    double s1, s2, s3;
    symmetricEigenvalues(a, s1, s2, s3);
    std::sort(ev, ev + 3);
    // acos is ill-conditioned at a repeated root: error ~ sqrt(eps) * |A| there, ~ eps * |A| otherwise.
    const double tol = trial % 10 == 0 ? 1e-5 : 1e-9;
    EXPECT_NEAR(s1, ev[2], tol);
    EXPECT_NEAR(s2, ev[1], tol);
    EXPECT_NEAR(s3, ev[0], tol);
    EXPECT_NEAR(trescaShearPrincipal(a), (ev[2] - ev[0]) / 2, tol);
    if (trial % 10 != 0) {
      const Vec3d v = symmetricEigenvector(a, s1);
      EXPECT_NEAR(norm(v), 1.0, 1e-9);
      EXPECT_NEAR(norm(a * v - v * s1), 0.0, 1e-6);
    }
  }
}

TEST(TearingTresca, BondStressOfUniaxialStretchAgreesWithBondExtrema) {
  // Particle at the origin with four bonds (+-x, +-y), stretched 20 % along x only: the bond extrema give
  // (k 0.2 - 0) / 2; the bond stress tensor has eigenvalues (k 0.2 / 2, 0, 0) in the virial average, i.e.
  // the same principal direction and a shear smaller by the averaging factor 1/2 (docs/tearing.md).
  const double k = 1000;
  Mat3d sigma;
  StrainExtrema<double> e;
  const Vec3d xi(0, 0, 0);
  const Vec3d nb[4] = {Vec3d(1.2, 0, 0), Vec3d(-1.2, 0, 0), Vec3d(0, 1, 0), Vec3d(0, -1, 0)};
  for (int b = 0; b < 4; ++b) {
    accumulateBondStress(sigma, xi, nb[b], 1.0, k);
    accumulateStrain(e, bondStrain(xi, nb[b], 1.0), b);
  }
  sigma *= 0.25;
  EXPECT_NEAR(trescaShear(k, e.rho_max, e.rho_min), 100.0, 1e-9);
  EXPECT_NEAR(trescaShearPrincipal(sigma), 50.0, 1e-6);  // repeated root 0: sqrt(eps) conditioning
  double s1, s2, s3;
  symmetricEigenvalues(sigma, s1, s2, s3);
  const Vec3d v = symmetricEigenvector(sigma, s1);
  EXPECT_NEAR(std::fabs(v.x), 1.0, 1e-9);
}

TEST(TearingTresca, MoveCheckRejectsInversionAndDegeneracy) {
  const Vec3d b(1, 0, 0), c(0, 1, 0), a(0, 0, 0);
  EXPECT_TRUE(moveKeepsTriangle(a, Vec3d(0.2, 0.2, 0), b, c, 0.1));
  EXPECT_FALSE(moveKeepsTriangle(a, Vec3d(0.5, 0.5, 0), b, c, 0.1));  // onto the opposite edge
  EXPECT_FALSE(moveKeepsTriangle(a, Vec3d(0.8, 0.8, 0), b, c, 0.1));  // across it: inverted
  EXPECT_TRUE(onSplitSide(Vec3d(1, 1, 0), a, Vec3d(1, 0, 0)));
  EXPECT_FALSE(onSplitSide(Vec3d(-1, 1, 0), a, Vec3d(1, 0, 0)));
}
