// MLS elasticity math: kernel, moment matrices, patch test, rigid motion, exact forces, momentum, split energy.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "cpu_fallback/mls_pair_sums_cpu.h"
#include "cpu_fallback/mls_solver_cpu.h"
#include "host/assembly/mls_model_build.h"
#include "host/backends/solver_factory.h"
#include "model/mls_model.h"
#include "model/mls_solver.h"
#include "physics/mls_passes.h"
#include "tests/support/mls_test_scenes.h"

using namespace inc;
using namespace inc::mls_test;

namespace {

// Affine field u = M X + c with a non-symmetric M, evaluated at the precision-T rest positions.
Mat3d affineMatrix() { return Mat3d::fromRows({0.02, -0.015, 0.01}, {0.03, -0.01, 0.025}, {-0.02, 0.005, 0.015}); }

template <typename T>
double patchTestError(double jitter, std::int64_t& tested) {
  MlsBuildInput in = blockInput(7, 6, 5, 0.01, jitter, Vec3d(0.3, -0.2, 0.1));
  MlsModel<T> model = buildMlsModel<T>(in);
  MlsState<T> state;
  state.resize(model.size());
  const Mat3d m = affineMatrix();
  const Vec3d c(1e-3, -2e-3, 5e-4);
  for (std::size_t i = 0; i < model.size(); ++i) state.displacement[i] = Vec3<T>(m * Vec3d(model.rest[i]) + c);
  const MlsView<T> view = makeMlsView(model, state);
  double worst = 0;
  tested = 0;
  for (std::int64_t i = 0; i < view.n; ++i) {
    if (model.degeneracy[std::size_t(i)] != kMlsRegular) continue;
    const Mat3d g(mlsDisplacementGradient(view, i));
    worst = std::max(worst, frobeniusNorm(g - m) / frobeniusNorm(m));
    ++tested;
  }
  return worst;
}

// Total elastic energy of a model at displacement u (double), via pass 1.
double totalEnergy(const MlsModel<double>& model, MlsState<double>& state) {
  const MlsView<double> view = makeMlsView(model, state);
  double e = 0;
  for (std::int64_t i = 0; i < view.n; ++i) {
    mlsStressPass(view, i);
    e += state.energy[std::size_t(i)];
  }
  return e;
}

}  // namespace

TEST(MlsKernel, Eq4WeightIsNormalisedAndCompact) {
  const double h = 0.02;
  // Radial integral 4 pi r^2 w(r) dr over [0, h] with Simpson's rule: the kernel has unit mass.
  const int n = 2000;
  double integral = 0;
  for (int k = 0; k <= n; ++k) {
    const double r = h * k / n;
    const double wgt = (k == 0 || k == n) ? 1 : (k % 2 ? 4 : 2);
    integral += wgt * 4 * M_PI * r * r * mlsKernelWeight(r * r, h);
  }
  integral *= h / n / 3;
  EXPECT_NEAR(integral, 1.0, 1e-9);
  EXPECT_EQ(mlsKernelWeight(h * h, h), 0.0);
  EXPECT_EQ(mlsKernelWeight(4 * h * h, h), 0.0);
  // Same value as the literal eq. 4 form 315 / (64 pi h^9) (h^2 - r^2)^3.
  const double r2 = 0.3 * h * h;
  const double literal = 315.0 / (64.0 * M_PI * std::pow(h, 9)) * std::pow(h * h - r2, 3);
  EXPECT_NEAR(mlsKernelWeight(r2, h) / literal, 1.0, 1e-13);
  // The stable form does not underflow in float32 where h^9 would (h = 50 um).
  EXPECT_GT(mlsKernelWeight(0.0f, 5e-5f), 0.0f);
  EXPECT_TRUE(std::isfinite(mlsKernelWeight(0.0f, 5e-5f)));
}

TEST(MlsKernel, SymmetricEigenvaluesMatchConstruction) {
  // Q diag(1e-3, 2, 5) Q^T for a rotation Q: the closed form recovers the spectrum.
  const Mat3d q = rotation(Vec3d(1, 2, 3), 0.7);
  Mat3d d;
  d(0, 0) = 1e-3;
  d(1, 1) = 2;
  d(2, 2) = 5;
  const Mat3d a = q * d * transpose(q);
  double e0, e1, e2;
  symmetricEigenvalues(a, e0, e1, e2);
  EXPECT_NEAR(e0, 1e-3, 1e-13);
  EXPECT_NEAR(e1, 2, 1e-13);
  EXPECT_NEAR(e2, 5, 1e-13);
}

TEST(MlsKernel, DegenerateNeighbourhoodsGetFiniteRegularisedInverses) {
  const double h = 0.02, limit = 1e6;
  auto momentOf = [&](const std::vector<Vec3d>& xs, int& count) {
    Mat3d a;
    count = 0;
    for (const auto& x : xs) {
      const double w = mlsKernelWeight(norm2(x), h);
      count += w > 0;
      accumulateMomentMatrix(a, x, w);
    }
    return a;
  };
  int count = 0;
  // Coplanar: a ring in the z = 0 plane.
  std::vector<Vec3d> ring;
  for (int k = 0; k < 8; ++k) ring.push_back(Vec3d(0.01 * std::cos(k * 0.785), 0.01 * std::sin(k * 0.785), 0));
  // (moment first, then count: argument evaluation order is unspecified)
  Mat3d a_ring = momentOf(ring, count);
  MomentInverse<double> r = regularisedMomentInverse(a_ring, count, limit);
  EXPECT_TRUE(r.flags & kMlsCoplanar);
  EXPECT_FALSE(r.flags & kMlsCollinear);
  EXPECT_TRUE(r.flags & kMlsIllConditioned);
  EXPECT_TRUE(isFinite(r.inverse));
  // The ridge caps the condition number of A + eps I at the limit (relative 1e-9).
  double e0, e1, e2;
  symmetricEigenvalues(a_ring + Mat3d::diag(r.ridge), e0, e1, e2);
  EXPECT_NEAR(e2 / e0, limit, limit * 1e-9);
  // Collinear: points on the x axis.
  std::vector<Vec3d> line = {{0.005, 0, 0}, {-0.005, 0, 0}, {0.01, 0, 0}, {-0.012, 0, 0}, {0.015, 0, 0}};
  const Mat3d a_line = momentOf(line, count);
  r = regularisedMomentInverse(a_line, count, limit);
  EXPECT_TRUE(r.flags & kMlsCollinear);
  EXPECT_TRUE(isFinite(r.inverse));
  // Few neighbours (3, not coplanar): regularised although invertible.
  std::vector<Vec3d> three = {{0.01, 0, 0}, {0, 0.01, 0}, {0, 0, 0.01}};
  const Mat3d a_three = momentOf(three, count);
  r = regularisedMomentInverse(a_three, count, limit);
  EXPECT_EQ(count, 3);
  EXPECT_TRUE(r.flags & kMlsFewNeighbors);
  EXPECT_GT(r.ridge, 0.0);
  EXPECT_TRUE(isFinite(r.inverse));
  // Isolated: zero inverse, never NaN.
  r = regularisedMomentInverse(Mat3d(), 0, limit);
  EXPECT_TRUE(r.flags & kMlsIsolated);
  EXPECT_EQ(frobeniusNorm(r.inverse), 0.0);
  // Regular: isotropic lattice neighbourhood inverted exactly.
  std::vector<Vec3d> cube;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k)
        if (i || j || k) cube.push_back(Vec3d(i, j, k) * 0.008);
  const Mat3d a = momentOf(cube, count);
  r = regularisedMomentInverse(a, count, limit);
  EXPECT_EQ(r.flags, kMlsRegular);
  EXPECT_EQ(r.ridge, 0.0);
  const Mat3d id = a * r.inverse;
  for (int p = 0; p < 3; ++p)
    for (int q2 = 0; q2 < 3; ++q2) EXPECT_NEAR(id(p, q2), p == q2 ? 1.0 : 0.0, 1e-12);
}

TEST(MlsPatchTest, AffineFieldGivesExactGradientFloat64) {
  std::int64_t tested = 0;
  const double lattice = patchTestError<double>(0.0, tested);
  EXPECT_EQ(tested, 7 * 6 * 5);  // every lattice particle, boundary included, has a regular A_i
  const double jittered = patchTestError<double>(0.3, tested);
  std::printf("[ MLS ] patch test float64: lattice %.2e, jittered %.2e\n", lattice, jittered);
  EXPECT_LT(lattice, 1e-12);
  EXPECT_LT(jittered, 1e-12);
  EXPECT_GT(tested, 150);
}

TEST(MlsPatchTest, AffineFieldGivesExactGradientFloat32) {
  std::int64_t tested = 0;
  const double lattice = patchTestError<float>(0.0, tested);
  const double jittered = patchTestError<float>(0.3, tested);
  std::printf("[ MLS ] patch test float32: lattice %.2e, jittered %.2e\n", lattice, jittered);
  EXPECT_LT(lattice, 1e-5);
  EXPECT_LT(jittered, 1e-5);
  EXPECT_GT(tested, 150);
}

TEST(MlsStrain, GreenStrainIsHalfOfPapersTensor) {
  // E = 1/2 (F^T F - I); the paper's eq. 7 tensor F^T F - I is exactly 2 E.
  const Mat3d g = affineMatrix() * 10.0;
  const Mat3d f = Mat3d::identity() + g;
  const Mat3d paper = transpose(f) * f - Mat3d::identity();
  const Mat3d e = greenStrain(g);
  EXPECT_LT(frobeniusNorm(e * 2.0 - paper), 1e-15);
  // Small strain: E -> sym(G), the engineering infinitesimal strain.
  const Mat3d small = affineMatrix() * 1e-6;
  const Mat3d sym = (small + transpose(small)) * 0.5;
  EXPECT_LT(frobeniusNorm(greenStrain(small) - sym) / frobeniusNorm(sym), 1e-5);
  // det(I + G) - 1 from invariants agrees with the determinant.
  EXPECT_NEAR(volumeChange(g), det(f) - 1.0, 1e-15);
}

TEST(MlsStrain, VolumeSplitKeepsTheLinearMaterial) {
  // psi at a small strain eps: mu eps:eps + lambda_Lame/2 tr(eps)^2, whatever the volume penalty share.
  const double youngs = 5e3, nu = 0.45;
  double mu, lame;
  lameParameters(youngs, nu, mu, lame);
  const Mat3d g = affineMatrix() * 1e-4;
  const Mat3d eps = (g + transpose(g)) * 0.5;
  const double linear = mu * ddot(eps, eps) + 0.5 * lame * trace(eps) * trace(eps);
  for (double zeta : {0.0, 0.5, 1.0}) {
    const MlsCoefficients<double> c = mlsSplitCoefficients(youngs, nu, zeta > 0, zeta, 0.0);
    EXPECT_NEAR(mlsStressPoint(g, c).energy_density / linear, 1.0, 2e-3) << "zeta " << zeta;  // O(strain) terms
  }
  // zeta = 1 at a finite isochoric stretch stays positive (mu |dev E|^2 >= 0), and an inverted F costs energy.
  const MlsCoefficients<double> c = mlsSplitCoefficients(youngs, nu, true, 1.0, 0.0);
  Mat3d inv = Mat3d::diag(-1.0);
  inv(0, 0) = 1.0;  // F = diag(1, -1, -1) is a rotation: zero energy
  EXPECT_NEAR(mlsStressPoint(inv - Mat3d::identity(), c).energy_density, 0.0, 1e-9);
  Mat3d mirror = Mat3d::identity();
  mirror(2, 2) = -1.0;  // a reflection has E = 0 but J = -1
  EXPECT_NEAR(mlsStressPoint(mirror - Mat3d::identity(), c).energy_density, 0.5 * c.k_volume * 4.0, 1e-9);
  Mat3d stretch = Mat3d::diag(1.0 / std::sqrt(2.0));
  stretch(0, 0) = 2.0;
  EXPECT_GT(mlsStressPoint(stretch - Mat3d::identity(), c).energy_density, 0.0);
}

TEST(MlsForces, RigidRotationGivesZeroStrainAndForce) {
  for (const bool f64 : {true, false}) {
    MlsBuildInput in = blockInput(6, 5, 4, 0.01, 0.25);
    in.material.volume_preservation = true;
    auto solver = makeMlsSolver(in, BackendKind::Cpu, f64 ? Precision::Float64 : Precision::Float32);
    const std::vector<Vec3d> rest = solver->restPositions();
    const Mat3d r = rotation(Vec3d(1, -2, 0.5), 0.9);
    std::vector<Vec3d> u(rest.size());
    for (std::size_t i = 0; i < rest.size(); ++i) u[i] = r * rest[i] - rest[i] + Vec3d(0.01, 0.02, -0.03);
    solver->setDisplacements(u);
    solver->computeForces();
    std::vector<Vec3d> f;
    solver->forces(f);
    const MlsReduction red = solver->reduce();
    // Reference scale: the forces of a 1% stretch of the same block.
    std::vector<Vec3d> us(rest.size());
    for (std::size_t i = 0; i < rest.size(); ++i) us[i] = Vec3d(0.01 * (rest[i].x - solver->origin().x), 0, 0);
    solver->setDisplacements(us);
    solver->computeForces();
    std::vector<Vec3d> fs;
    solver->forces(fs);
    const double scale = maxNorm(fs);
    ASSERT_GT(scale, 0.0);
    EXPECT_LT(maxNorm(f) / scale, f64 ? 1e-10 : 2e-4) << (f64 ? "float64" : "float32");
    EXPECT_LT(red.elastic_energy, f64 ? 1e-18 : 1e-9);
  }
}

TEST(MlsForces, ForcesAreTheNegativeEnergyGradient) {
  // float64, jittered block, nonlinear deformation (several % strain + rotation), volume penalty on.
  MlsBuildInput in = blockInput(5, 4, 4, 0.01, 0.3);
  in.material.volume_preservation = true;
  in.material.volume_stiffness = 0.7;
  MlsModel<double> model = buildMlsModel<double>(in);
  MlsState<double> state;
  state.resize(model.size());
  const Mat3d r = rotation(Vec3d(0.3, 1, 0.2), 0.4);
  for (std::size_t i = 0; i < model.size(); ++i) {
    const Vec3d x = model.rest[i];
    const Vec3d noise(hashSigned(3 * i), hashSigned(3 * i + 1), hashSigned(3 * i + 2));
    state.displacement[i] = (r * (x + Vec3d(0.05 * x.x, -0.03 * x.y, 0.04 * x.z)) - x) + noise * 4e-4;
  }
  const MlsView<double> view = makeMlsView(model, state);
  for (std::int64_t i = 0; i < view.n; ++i) mlsStressPass(view, i);
  std::vector<Vec3d> f(model.size());
  for (std::int64_t k = 0; k < view.n; ++k) f[std::size_t(k)] = mlsElasticForce(view, k);
  const double fmax = maxNorm(f);
  ASSERT_GT(fmax, 0.0);
  const double eps = 1e-7;  // m; central difference truncation ~eps^2, rounding ~1e-16 U / eps
  double worst = 0;
  for (std::size_t k = 0; k < model.size(); ++k)
    for (int a = 0; a < 3; ++a) {
      const double keep = state.displacement[k][a];
      state.displacement[k][a] = keep + eps;
      const double up = totalEnergy(model, state);
      state.displacement[k][a] = keep - eps;
      const double down = totalEnergy(model, state);
      state.displacement[k][a] = keep;
      const double fd = -(up - down) / (2 * eps);
      worst = std::max(worst, std::abs(fd - f[k][a]) / fmax);
    }
  EXPECT_LT(worst, 1e-6);
}

TEST(MlsForces, MomentumAndAngularMomentumAreConserved) {
  for (const bool f64 : {true, false}) {
    MlsBuildInput in = blockInput(6, 5, 5, 0.01, 0.3);
    in.material.volume_preservation = true;
    auto solver = makeMlsSolver(in, BackendKind::Cpu, f64 ? Precision::Float64 : Precision::Float32);
    const std::vector<Vec3d> rest = solver->restPositions();
    std::vector<Vec3d> u(rest.size());
    for (std::size_t i = 0; i < u.size(); ++i)
      u[i] = Vec3d(hashSigned(i), hashSigned(i + 7777), hashSigned(i + 99999)) * 2e-3;
    solver->setDisplacements(u);
    solver->computeForces();
    std::vector<Vec3d> f, x;
    solver->forces(f);
    solver->positions(x);
    Vec3d sum, torque, centroid;
    double mag = 0, tmag = 0;
    for (const auto& p : x) centroid += p * (1.0 / double(x.size()));
    for (std::size_t i = 0; i < f.size(); ++i) {
      sum += f[i];
      torque += cross(x[i] - centroid, f[i]);
      mag += norm(f[i]);
      tmag += norm(x[i] - centroid) * norm(f[i]);
    }
    const double tol = f64 ? 1e-12 : 1e-5;
    EXPECT_LT(norm(sum) / mag, tol) << (f64 ? "float64" : "float32");
    EXPECT_LT(norm(torque) / tmag, tol) << (f64 ? "float64" : "float32");
  }
}

// The CPU's float32 passes use AVX2 pair sums where the CPU has them (cpu_fallback/mls_pair_sums_cpu.cpp) and the
// portable loops of physics/mls_passes.h elsewhere: the two must give the same bits (forces, energies and a run of
// substeps on a jittered, strained, volume-preserving block), and agree with the recomputing (GPU) sums to 1e-5.
TEST(MlsForces, VectorPairSumsMatchThePortableLoopBitForBit) {
  if (!cpu::mlsPairSumsUseAvx2()) GTEST_SKIP() << "no AVX2 on this CPU: only the portable loops exist here";
  MlsBuildInput in = blockInput(9, 8, 7, 0.01, 0.3);
  in.material.volume_preservation = true;
  in.material.damping_per_s = 2.0;
  in.gravity = Vec3d(0, 0, -9.81);
  std::vector<Vec3d> u;
  std::vector<Vec3d> f[2], x[2];
  std::vector<double> e[2];
  for (const bool portable : {false, true}) {
    cpu::setMlsPairSumsPortable(portable);
    auto solver = makeMlsSolver(in, BackendKind::Cpu, Precision::Float32);
    const std::vector<Vec3d> rest = solver->restPositions();
    u.resize(rest.size());
    for (std::size_t i = 0; i < u.size(); ++i)
      u[i] = Vec3d(hashSigned(i), hashSigned(i + 7777), hashSigned(i + 99999)) * 2e-3;
    solver->setDisplacements(u);
    solver->computeForces();
    solver->forces(f[portable]);
    solver->energies(e[portable]);
    solver->step(0.5 * solver->stableTimeStep(), 40);
    solver->displacements(x[portable]);
  }
  cpu::setMlsPairSumsPortable(false);
  ASSERT_EQ(f[0].size(), f[1].size());
  for (std::size_t i = 0; i < f[0].size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      ASSERT_EQ(f[0][i][c], f[1][i][c]) << "force of particle " << i;
      ASSERT_EQ(x[0][i][c], x[1][i][c]) << "displacement of particle " << i << " after 40 substeps";
    }
    ASSERT_EQ(e[0][i], e[1][i]) << "energy of particle " << i;
  }
  // Against the recomputing sums (no pair tables, the CUDA kernels' form) at the same displacement, in float32.
  MlsModel<float> model = buildMlsModel<float>(in);
  MlsState<float> state;
  state.resize(model.size());
  for (std::size_t i = 0; i < u.size(); ++i) state.displacement[i] = Vec3f(u[i]);
  const MlsView<float> view = makeMlsView(model, state);
  for (std::int64_t i = 0; i < view.n; ++i) mlsStressPass(view, i);
  double worst = 0, fmax = 0;
  for (std::int64_t k = 0; k < view.n; ++k) {
    const Vec3d fk(mlsElasticForce(view, k));
    worst = std::max(worst, norm(fk - f[0][std::size_t(k)]));
    fmax = std::max(fmax, norm(fk));
  }
  EXPECT_LT(worst, 1e-5 * fmax);
}
