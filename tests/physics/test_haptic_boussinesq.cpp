// Tests of the Boussinesq-Cerruti half-space solutions: surface values, free surface, equilibrium, reciprocity.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "physics/boussinesq.h"

namespace inc {
namespace {

const double kE = 3e3, kNu = 0.45, kG = kE / (2.0 * (1.0 + kNu));

TEST(HapticBoussinesq, SurfaceDisplacementsMatchTheClassicalFormulas) {
  for (double r : {1e-3, 7e-3, 0.05}) {
    const Mat3d b = boussinesqCerrutiDisplacement(Vec3d{r * 0.6, r * 0.8, 0.0}, kG, kNu);
    // Normal force (+z, pulling out): the surface rises by (1 - nu^2) / (pi E r) per newton, and moves
    // radially outward by (1 - 2 nu) / (4 pi G r) (a push draws it in).
    const double w = (1 - kNu * kNu) / (M_PI * kE * r), ur = (1 - 2 * kNu) / (4 * M_PI * kG * r);
    EXPECT_NEAR(b(2, 2), w, 1e-12 * w);
    EXPECT_NEAR(b(2, 0), ur * 0.6, 1e-12 * ur);
    EXPECT_NEAR(b(2, 1), ur * 0.8, 1e-12 * ur);
    // Tangential force along x: u_x = ((1 - nu) + nu x^2 / r^2) / (2 pi G r) on the surface.
    const double ux = ((1 - kNu) + kNu * 0.36) / (2 * M_PI * kG * r);
    EXPECT_NEAR(b(0, 0), ux, 1e-12 * ux);
  }
}

// Traction t = sigma n of the field of a unit force along k.
Vec3d traction(const Vec3d& x, int k, const Vec3d& n) {
  const Mat3d s = boussinesqCerrutiStress(x, k, kG, kNu);
  return {s(0, 0) * n.x + s(0, 1) * n.y + s(0, 2) * n.z, s(1, 0) * n.x + s(1, 1) * n.y + s(1, 2) * n.z,
          s(2, 0) * n.x + s(2, 1) * n.y + s(2, 2) * n.z};
}

TEST(HapticBoussinesq, SurfaceIsFreeOfTraction) {
  for (int k = 0; k < 3; ++k)
    for (double phi : {0.3, 1.9, 4.0}) {
      const double r = 4e-3;
      const Vec3d x{r * std::cos(phi), r * std::sin(phi), 0.0};
      const Mat3d s = boussinesqCerrutiStress(x, k, kG, kNu);
      double scale = 0.0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) scale = std::max(scale, std::fabs(s(i, j)));
      ASSERT_GT(scale, 0.0);
      const Vec3d t = traction(x, k, {0, 0, 1});
      EXPECT_LT(norm(t), 1e-6 * scale) << "force " << k << " phi " << phi;  // central differences ~1e-8
    }
}

// Integral of the traction over the sphere |x - c| = rho inside the solid (Gauss-Legendre in the polar angle,
// trapezoid in azimuth); `lower_half`: only z < 0 around the origin (the half-ball cut by the free surface).
Vec3d sphereForce(const Vec3d& c, double rho, int k, bool lower_half) {
  const int nt = 48, np = 96;
  std::vector<double> x(nt), w(nt);
  for (int i = 0; i < nt; ++i) {  // Gauss-Legendre on [-1, 1] by Newton iteration
    double z = std::cos(M_PI * (i + 0.75) / (nt + 0.5)), dp = 1;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = z;
      for (int m = 2; m <= nt; ++m) {
        const double p2 = ((2 * m - 1) * z * p1 - (m - 1) * p0) / m;
        p0 = p1;
        p1 = p2;
      }
      dp = nt * (z * p1 - p0) / (z * z - 1);
      const double dz = p1 / dp;
      z -= dz;
      if (std::fabs(dz) < 1e-15) break;
    }
    x[i] = z;
    w[i] = 2.0 / ((1 - z * z) * dp * dp);
  }
  Vec3d f;
  const double c_lo = -1.0, c_hi = lower_half ? 0.0 : 1.0;  // range of the cosine of the polar angle
  for (int i = 0; i < nt; ++i) {
    const double ct = c_lo + (c_hi - c_lo) * 0.5 * (x[i] + 1.0), st = std::sqrt(1 - ct * ct);
    const double wt = w[i] * 0.5 * (c_hi - c_lo);
    for (int j = 0; j < np; ++j) {
      const double ph = 2 * M_PI * (j + 0.5) / np;
      const Vec3d n{st * std::cos(ph), st * std::sin(ph), ct};
      f += traction(c + n * rho, k, n) * (wt * (2 * M_PI / np) * rho * rho);
    }
  }
  return f;
}

TEST(HapticBoussinesq, TheFieldBalancesThePointForceAndIsInEquilibrium) {
  for (int k = 0; k < 3; ++k) {
    Vec3d e;
    e[k] = 1.0;
    // Half-ball around the load (its flat face is the free surface): the tractions on its curved face
    // balance the unit force, whatever the radius.
    for (double rho : {2e-3, 2e-2}) {
      const Vec3d f = sphereForce({0, 0, 0}, rho, k, true);
      EXPECT_NEAR(norm(f + e), 0.0, 1e-6) << "force " << k << " rho " << rho;
    }
    // A small ball inside the solid away from the load carries no net force (div sigma = 0).
    const Vec3d f = sphereForce({3e-3, -2e-3, -4e-3}, 1e-3, k, false);
    EXPECT_NEAR(norm(f), 0.0, 1e-6) << "force " << k;
  }
}

TEST(HapticBoussinesq, SurfaceResponseIsReciprocal) {
  // Betti: u_l at x for a unit force k at 0 equals u_k at 0 for a unit force l at x, i.e. B(x)(k, l) = B(-x)(l, k).
  for (const Vec3d x : {Vec3d{3e-3, 1e-3, 0.0}, Vec3d{-2e-3, 5e-3, 0.0}}) {
    const Mat3d b = boussinesqCerrutiDisplacement(x, kG, kNu), bm = boussinesqCerrutiDisplacement(x * -1.0, kG, kNu);
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) EXPECT_NEAR(b(k, l), bm(l, k), 1e-12 * std::fabs(b(0, 0)));
  }
}

}  // namespace
}  // namespace inc
