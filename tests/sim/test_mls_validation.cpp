// MLS solid against analytic answers: homogeneous SVK stress, Poisson contraction, cantilever vs Euler-Bernoulli,
// gradient convergence order, stable-step calibration, energy conservation, step refusal and extreme materials.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "host/assembly/mls_model_build.h"
#include "host/backends/solver_factory.h"
#include "model/mls_model.h"
#include "model/mls_solver.h"
#include "physics/mls_passes.h"
#include "tests/support/mls_test_scenes.h"

using namespace inc;
using namespace inc::mls_test;

namespace {

// Elastic forces of a float64 model at displacement u (passes 1 and 2 of physics/mls_passes.h).
std::vector<Vec3d> forcesAt(const MlsModel<double>& model, MlsState<double>& state, const std::vector<Vec3d>& u) {
  state.displacement = u;
  const MlsView<double> view = makeMlsView(model, state);
  for (std::int64_t i = 0; i < view.n; ++i) mlsStressPass(view, i);
  std::vector<Vec3d> f(model.size());
  for (std::int64_t k = 0; k < view.n; ++k) f[std::size_t(k)] = mlsElasticForce(view, k);
  return f;
}

double dotAll(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += dot(a[i], b[i]);
  return s;
}

// Static small-strain equilibrium K u = f_ext with u = u_fixed on the non-free particles, by conjugate
// gradients with the matrix-free operator K v = -f(eps v) / eps (SVK is linear to O(eps) at rest).
std::vector<Vec3d> solveStatic(const MlsModel<double>& model, const std::vector<Vec3d>& f_ext,
                               const std::vector<Vec3d>& u_fixed, double rel_tol, int max_iter) {
  MlsState<double> state;
  state.resize(model.size());
  const std::size_t n = model.size();
  auto freeOnly = [&](std::vector<Vec3d>& v) {
    for (std::size_t i = 0; i < n; ++i)
      if (model.kind[i] != kMlsFree) v[i] = Vec3d();
  };
  auto apply = [&](const std::vector<Vec3d>& v) {
    double vmax = 0;
    for (const auto& x : v) vmax = std::max(vmax, norm(x));
    std::vector<Vec3d> out(n);
    if (vmax == 0) return out;
    const double eps = 1e-7 * double(model.spacing) / vmax;  // strain ~1e-7
    std::vector<Vec3d> scaled(n);
    for (std::size_t i = 0; i < n; ++i) scaled[i] = v[i] * eps;
    const std::vector<Vec3d> f = forcesAt(model, state, scaled);
    for (std::size_t i = 0; i < n; ++i) out[i] = f[i] * (-1.0 / eps);
    freeOnly(out);
    return out;
  };
  std::vector<Vec3d> u(n);
  for (std::size_t i = 0; i < n; ++i) u[i] = model.kind[i] != kMlsFree ? u_fixed[i] : Vec3d();
  // r = f_ext - K u0 on the free particles.
  std::vector<Vec3d> r = apply(u);
  for (std::size_t i = 0; i < n; ++i) r[i] = f_ext[i] - r[i];
  freeOnly(r);
  std::vector<Vec3d> p = r;
  double rr = dotAll(r, r);
  const double r0 = std::sqrt(rr);
  for (int it = 0; it < max_iter && std::sqrt(rr) > rel_tol * r0; ++it) {
    const std::vector<Vec3d> kp = apply(p);
    const double alpha = rr / dotAll(p, kp);
    for (std::size_t i = 0; i < n; ++i) {
      u[i] += p[i] * alpha;
      r[i] -= kp[i] * alpha;
    }
    const double rr_new = dotAll(r, r);
    for (std::size_t i = 0; i < n; ++i) p[i] = r[i] + p[i] * (rr_new / rr);
    rr = rr_new;
  }
  EXPECT_LE(std::sqrt(rr), rel_tol * r0 * 1.0001) << "CG did not converge";
  return u;
}

// Cantilever of length L (x), square section b x b, clamped by `clamp_layers` particle layers at x = min,
// under its own weight (gravity -z). Returns the mean tip deflection over the last layer (m, positive down).
double cantileverTipDeflection(double spacing, double length, double b, double youngs, double nu, double rho, double g,
                               double& eb, double support_factor = 2.0) {
  const int clamp_layers = 2;
  MlsBuildInput in;
  const int nx = int(std::lround(length / spacing)) + clamp_layers;
  const int nb = int(std::lround(b / spacing));
  in.rest_positions =
      sampleBox(Vec3d(0, 0, 0), Vec3d(nx * spacing, nb * spacing, nb * spacing), LatticeSpec{spacing, 0.0, 1});
  in.spacing = spacing;
  in.support_factor = support_factor;
  in.material.youngs_modulus_pa = youngs;
  in.material.poisson_ratio = nu;
  in.material.density_kg_m3 = rho;
  in.material.damping_per_s = 0;
  in.material.volume_preservation = true;
  in.gravity = Vec3d(0, 0, -g);
  const double x0 = -0.5 * nx * spacing;  // clamp face of the lattice block
  in.kinds.resize(in.rest_positions.size());
  for (std::size_t i = 0; i < in.kinds.size(); ++i)
    in.kinds[i] = in.rest_positions[i].x < x0 + clamp_layers * spacing ? kMlsFixed : kMlsFree;
  MlsModel<double> model = buildMlsModel<double>(in);
  std::vector<Vec3d> f_ext(model.size()), u_fixed(model.size());
  for (std::size_t i = 0; i < model.size(); ++i) f_ext[i] = in.gravity * model.mass[i];
  const std::vector<Vec3d> u = solveStatic(model, f_ext, u_fixed, 1e-8, 4000);
  double xmax = -1e30, tip = 0;
  int count = 0;
  for (std::size_t i = 0; i < model.size(); ++i) xmax = std::max(xmax, double(model.rest[i].x));
  for (std::size_t i = 0; i < model.size(); ++i)
    if (model.rest[i].x > xmax - 0.5 * spacing) {
      tip += -u[i].z;
      ++count;
    }
  // Euler-Bernoulli: delta = q L^4 / (8 E I), q = rho g b^2 (N/m), I = b^4 / 12; the free length runs from
  // the last clamped layer's cell face to the tip cell's face: (nx - clamp_layers) * spacing.
  const double L = (nx - clamp_layers) * spacing;
  const double bb = nb * spacing;
  eb = rho * g * bb * bb * std::pow(L, 4) / (8.0 * youngs * std::pow(bb, 4) / 12.0);
  return tip / count;
}

}  // namespace

TEST(MlsValidation, HomogeneousStretchGivesAnalyticSvkStress) {
  // F = diag(1.05, 0.98, 0.99) with a shear: every regular particle's P equals F S, S = lambda tr(E) I + 2 mu E,
  // E = 1/2 (F^T F - I) (relative 1e-10 in float64). With the volume penalty the split form is checked too.
  for (const bool vp : {false, true}) {
    MlsBuildInput in = blockInput(6, 5, 5, 0.01, 0.2);
    in.material.volume_preservation = vp;
    MlsModel<double> model = buildMlsModel<double>(in);
    MlsState<double> state;
    state.resize(model.size());
    Mat3d f = Mat3d::diag(1.0);
    f(0, 0) = 1.05;
    f(1, 1) = 0.98;
    f(2, 2) = 0.99;
    f(0, 1) = 0.02;
    for (std::size_t i = 0; i < model.size(); ++i) state.displacement[i] = (f - Mat3d::identity()) * model.rest[i];
    double mu, lame;
    lameParameters(in.material.youngs_modulus_pa, in.material.poisson_ratio, mu, lame);
    const Mat3d e = (transpose(f) * f - Mat3d::identity()) * 0.5;
    Mat3d p = f * (e * (2 * mu) + Mat3d::diag(lame * trace(e)));
    if (vp) {  // psi = mu E:E + (lambda - K)/2 tr(E)^2 + K/2 (J - 1)^2 (volume_stiffness 1)
      const double bulk = lame + 2 * mu / 3, j = det(f);
      p = f * (e * (2 * mu) + Mat3d::diag((lame - bulk) * trace(e))) + transpose(adjugate(f)) * (bulk * (j - 1));
    }
    const MlsView<double> view = makeMlsView(model, state);
    int tested = 0;
    for (std::int64_t i = 0; i < view.n; ++i) {
      if (model.degeneracy[std::size_t(i)] != kMlsRegular) continue;
      const Mat3d g = mlsDisplacementGradient(view, i);
      const MlsStressPoint<double> sp = mlsStressPoint(g, model.coeffs);
      EXPECT_LT(frobeniusNorm(sp.piola - p) / frobeniusNorm(p), 1e-10) << "particle " << i;
      ++tested;
    }
    EXPECT_GT(tested, 100);
  }
}

TEST(MlsValidation, UniaxialStretchContractsByPoissonRatio) {
  // A bar 16 x 4 x 4 particles, ends held (x = min fixed, x = max pulled 0.1% along x): in the middle third
  // the lateral strain over the axial strain is -nu within 5% (Saint-Venant: the end constraint decays).
  for (const double nu : {0.3, 0.45}) {
    MlsBuildInput in = blockInput(16, 4, 4, 0.01);
    in.material.poisson_ratio = nu;
    in.material.volume_preservation = true;
    in.kinds.resize(in.rest_positions.size());
    const double half = 0.08;
    for (std::size_t i = 0; i < in.kinds.size(); ++i)
      in.kinds[i] = std::abs(in.rest_positions[i].x) > half - 0.01 ? kMlsFixed : kMlsFree;
    MlsModel<double> model = buildMlsModel<double>(in);
    std::vector<Vec3d> f_ext(model.size()), u_fixed(model.size());
    for (std::size_t i = 0; i < model.size(); ++i)
      if (model.kind[i] != kMlsFree && model.rest[i].x > 0) u_fixed[i] = Vec3d(1.6e-4, 0, 0);
    const std::vector<Vec3d> u = solveStatic(model, f_ext, u_fixed, 1e-9, 3000);
    MlsState<double> state;
    state.resize(model.size());
    state.displacement = u;
    const MlsView<double> view = makeMlsView(model, state);
    double axial = 0, lateral = 0;
    int count = 0;
    for (std::int64_t i = 0; i < view.n; ++i) {
      if (std::abs(model.rest[std::size_t(i)].x) > 0.025) continue;
      const Mat3d g = mlsDisplacementGradient(view, i);
      axial += g(0, 0);
      lateral += 0.5 * (g(1, 1) + g(2, 2));
      ++count;
    }
    ASSERT_GT(count, 0);
    const double ratio = -lateral / axial;
    std::printf("[ MLS ] uniaxial stretch nu = %.2f: measured -e_lat/e_ax = %.4f\n", nu, ratio);
    EXPECT_NEAR(ratio / nu, 1.0, 0.05) << "nu " << nu;
  }
}

TEST(MlsValidation, CantileverMatchesEulerBernoulliAndConverges) {
  // L = 0.2 m, b = 0.02 m, E = 50 MPa, nu = 0.3, rho = 1000: EB tip deflection 1.18 mm (0.6% of L; the static
  // solve is linear anyway). Static equilibrium by CG at spacings b/4 and b/6 with support 1.5 spacings (the
  // most accurate in bending, see DISABLED_CantileverStudy and docs/mls.md). Asserted: the finer is within
  // 10% of EB, and the error falls with the spacing at an observed order >= 1.
  const double L = 0.2, b = 0.02, youngs = 5e7, nu = 0.3, rho = 1000, g = 9.81, support = 1.5;
  double eb_c = 0, eb_f = 0;
  const double hc = b / 4, hf = b / 6;
  const double dc = cantileverTipDeflection(hc, L, b, youngs, nu, rho, g, eb_c, support);
  const double df = cantileverTipDeflection(hf, L, b, youngs, nu, rho, g, eb_f, support);
  const double err_c = std::abs(dc / eb_c - 1), err_f = std::abs(df / eb_f - 1);
  const double order = std::log(err_c / err_f) / std::log(hc / hf);
  const double r = (hc / hf) * (hc / hf);
  const double extrapolated = df + (df - dc) / (r - 1);
  std::printf(
      "[ MLS ] cantilever tip: spacing %.4f m: %.4e m (EB %.4e, err %.1f%%); spacing %.4f m: %.4e m (err "
      "%.1f%%); observed order %.2f; Richardson (p = 2) %.4e m (err %.2f%%)\n",
      hc, dc, eb_c, 100 * err_c, hf, df, 100 * err_f, order, extrapolated, 100 * std::abs(extrapolated / eb_f - 1));
  EXPECT_NEAR(eb_c, eb_f, 1e-12);
  EXPECT_LT(err_f, 0.10);
  EXPECT_GT(order, 1.0);
}

TEST(MlsValidation, GradientOfQuadraticFieldConvergesWithSpacing) {
  // u = (x^2, x y, z^2) / L over a fixed cube, jittered lattice: the RMS MLS (linear) gradient error at
  // interior particles falls at least linearly with the spacing (observed order printed; >= 0.9 asserted).
  // (On an unjittered lattice the odd moments vanish and the interior gradient of a quadratic is exact.)
  auto error = [](int n) {
    const double size = 0.06, s = size / n;
    MlsBuildInput in = blockInput(n, n, n, s, 0.25);
    MlsModel<double> model = buildMlsModel<double>(in);
    MlsState<double> state;
    state.resize(model.size());
    const double L = 0.1;
    for (std::size_t i = 0; i < model.size(); ++i) {
      const Vec3d x = model.rest[i];
      state.displacement[i] = Vec3d(x.x * x.x, x.x * x.y, x.z * x.z) * (1 / L);
    }
    const MlsView<double> view = makeMlsView(model, state);
    double sum2 = 0;
    int count = 0;
    for (std::int64_t i = 0; i < view.n; ++i) {
      const Vec3d x = model.rest[std::size_t(i)];
      if (std::max({std::abs(x.x), std::abs(x.y), std::abs(x.z)}) > 0.5 * size - 2.5 * s) continue;
      const Mat3d exact = Mat3d::fromRows({2 * x.x, 0, 0}, {x.y, x.x, 0}, {0, 0, 2 * x.z}) * (1 / L);
      const double e = frobeniusNorm(mlsDisplacementGradient(view, i) - exact);
      sum2 += e * e;
      ++count;
    }
    return std::sqrt(sum2 / count);
  };
  const double e1 = error(10), e2 = error(20);
  const double order = std::log(e1 / e2) / std::log(2.0);
  std::printf("[ MLS ] gradient error of a quadratic field: %.3e (n=10) -> %.3e (n=20), order %.2f\n", e1, e2, order);
  EXPECT_GT(order, 0.9);
}

TEST(MlsValidation, StableStepIsBelowTheDiscreteLimit) {
  // Largest eigenfrequency of M^{-1} K (power iteration with K v = -f(eps v)/eps): leapfrog is stable for
  // dt < 2 / omega_max; the solver's limit (kMlsCourant spacing / c_p) must be below it, for several
  // Poisson ratios, the volume penalty and jitter.
  for (const double nu : {0.0, 0.3, 0.45, 0.49, 0.499}) {
    MlsBuildInput in = blockInput(6, 6, 6, 0.01, 0.2);
    in.material.poisson_ratio = nu;
    in.material.volume_preservation = true;
    MlsModel<double> model = buildMlsModel<double>(in);
    MlsState<double> state;
    state.resize(model.size());
    std::vector<Vec3d> v(model.size());
    for (std::size_t i = 0; i < v.size(); ++i)
      v[i] = Vec3d(hashSigned(3 * i), hashSigned(3 * i + 1), hashSigned(3 * i + 2));
    double omega2 = 0;
    for (int it = 0; it < 300; ++it) {
      const double vn = std::sqrt(dotAll(v, v));
      for (auto& x : v) x = x * (1e-9 / vn);
      const std::vector<Vec3d> f = forcesAt(model, state, v);
      std::vector<Vec3d> y(v.size());
      for (std::size_t i = 0; i < v.size(); ++i) y[i] = f[i] * (-1.0 / (1e-9 * model.mass[i]));
      omega2 = dotAll(v, y) / dotAll(v, v) * 1e-9;  // Rayleigh quotient (v scaled to 1e-9)
      v = y;
    }
    const double limit = 2.0 / std::sqrt(omega2);
    std::printf("[ MLS ] nu = %.2f: discrete limit %.3e s, solver limit %.3e s (ratio %.2f)\n", nu, limit,
                model.stats.stable_dt, limit / model.stats.stable_dt);
    EXPECT_LT(model.stats.stable_dt, limit) << "nu " << nu;
  }
}

TEST(MlsValidation, UndampedLeapfrogConservesEnergy) {
  // A free block vibrating from a smooth initial stretch, no gravity, no damping, 10^4 steps at the solver's
  // step (safety 0.5): the energy drift (mean total energy of the last 10% of the run against the first 10%)
  // stays under 1%; the bounded leapfrog oscillation of the total energy stays under 5%.
  for (const Precision prec : {Precision::Float64, Precision::Float32}) {
    MlsBuildInput in = blockInput(4, 4, 4, 0.01, 0.2);
    in.material.volume_preservation = true;
    auto solver = makeMlsSolver(in, BackendKind::Cpu, prec);
    const std::vector<Vec3d> rest = solver->restPositions();
    std::vector<Vec3d> u(rest.size());
    for (std::size_t i = 0; i < u.size(); ++i) {
      const Vec3d x = rest[i] - solver->origin();
      u[i] = Vec3d(0.03 * x.x + 0.5 * x.y * x.y, -0.01 * x.y, 0.02 * x.z * x.x / 0.05);
    }
    solver->setDisplacements(u);
    const double e0 = solver->reduce().total();
    ASSERT_GT(e0, 0.0);
    const double dt = solver->safety() * solver->stableTimeStep();
    double worst = 0, first = 0, last = 0;
    const int chunks = 200, per = 50;
    for (int chunk = 0; chunk < chunks; ++chunk) {
      solver->step(dt, per);
      const MlsReduction r = solver->reduce();
      ASSERT_TRUE(r.finite);
      worst = std::max(worst, std::abs(r.total() / e0 - 1));
      if (chunk < chunks / 10) first += r.total() / (chunks / 10);
      if (chunk >= chunks - chunks / 10) last += r.total() / (chunks / 10);
    }
    std::printf("[ MLS ] %s: energy drift over 1e4 steps %.2e, max oscillation %.2e\n", precisionName(prec),
                std::abs(last / first - 1), worst);
    EXPECT_LT(std::abs(last / first - 1), 0.01);
    EXPECT_LT(worst, 0.05);
  }
}

TEST(MlsValidation, UnstableStepsAreRefusedOrSubstepped) {
  MlsBuildInput in = blockInput(4, 4, 4, 0.01);
  auto solver = makeMlsSolver(in, BackendKind::Cpu, Precision::Float32);
  const double limit = solver->stableTimeStep();
  EXPECT_THROW(solver->step(2.0 * limit, 1), InputError);
  EXPECT_NO_THROW(solver->step(0.5 * limit, 1));
  // A frame of 10 stable steps: 2 fixed substeps are refused, automatic substepping takes >= 10 / safety.
  EXPECT_THROW(solver->advance(10 * limit, 2), InputError);
  const MlsFrameStats st = solver->advance(10 * limit);
  EXPECT_GE(st.substeps, int(std::floor(10 / solver->safety())));
  EXPECT_LE(st.dt, solver->safety() * limit * (1 + 1e-12));
  EXPECT_TRUE(st.totals.finite);
}

TEST(MlsValidation, ExtremeMaterialsStayFiniteAndBounded) {
  // Poisson ratios 0 .. 0.499 and Young's moduli 1e2 .. 1e9 Pa: a block clamped at x = min, started from a
  // smooth 2% strain field plus 0.1% noise, damped, 2000 substeps: every frame finite and the total energy
  // never above its initial value (+1%: leapfrog's bounded oscillation).
  for (const double nu : {0.0, 0.3, 0.45, 0.49, 0.499})
    for (const double youngs : {1e2, 1e5, 1e9}) {
      MlsBuildInput in = blockInput(6, 3, 3, 0.01, 0.1);
      in.material.poisson_ratio = nu;
      in.material.youngs_modulus_pa = youngs;
      in.material.volume_preservation = true;
      in.material.damping_per_s = 5.0;
      in.kinds.resize(in.rest_positions.size());
      for (std::size_t i = 0; i < in.kinds.size(); ++i)
        in.kinds[i] = in.rest_positions[i].x < -0.02 ? kMlsFixed : kMlsFree;
      auto solver = makeMlsSolver(in, BackendKind::Cpu, Precision::Float32);
      const std::vector<Vec3d> rest = solver->restPositions();
      std::vector<Vec3d> u(rest.size());
      for (std::size_t i = 0; i < u.size(); ++i) {
        const Vec3d x = rest[i] - solver->origin();
        if (in.kinds[i] == kMlsFixed) continue;
        u[i] = Vec3d(0.02 * x.x, -0.01 * x.x * x.y / 0.03, 0.02 * x.x * x.x / 0.03) +
               Vec3d(hashSigned(3 * i), hashSigned(3 * i + 1), hashSigned(3 * i + 2)) * 1e-5;
      }
      solver->setDisplacements(u);
      const double e0 = solver->reduce().total();
      const double frame = 400 * solver->safety() * solver->stableTimeStep();
      for (int k = 0; k < 5; ++k) {
        const MlsFrameStats st = solver->advance(frame);
        ASSERT_TRUE(st.totals.finite) << "nu " << nu << " E " << youngs << ": " << st.totals.bad_stage << " particle "
                                      << st.totals.first_bad;
        EXPECT_LE(st.totals.total(), e0 * 1.01) << "nu " << nu << " E " << youngs << " frame " << k;
      }
    }
}

TEST(MlsValidation, SoftBlockBeyondItsStrengthHangsWithoutBlowingUp) {
  // A 100 Pa block 6 cm long clamped at one end cannot carry its own weight (rho g L / E ~ 6): it sags into a
  // strongly stretched hanging shape (SVK stiffens ~100x). Every frame stays finite, the planned substeps grow
  // with the stiffening, and the energy obeys the work bound (kinetic + strain <= work of gravity).
  MlsBuildInput in = blockInput(6, 3, 3, 0.01, 0.1);
  in.material.youngs_modulus_pa = 1e2;
  in.material.poisson_ratio = 0.0;
  in.material.volume_preservation = true;
  in.material.damping_per_s = 5.0;
  in.gravity = Vec3d(0, 0, -9.81);
  in.kinds.resize(in.rest_positions.size());
  for (std::size_t i = 0; i < in.kinds.size(); ++i) in.kinds[i] = in.rest_positions[i].x < -0.02 ? kMlsFixed : kMlsFree;
  auto solver = makeMlsSolver(in, BackendKind::Cpu, Precision::Float32);
  const double frame = 400 * solver->safety() * solver->stableTimeStep();
  MlsFrameStats st;
  for (int k = 0; k < 8; ++k) {
    st = solver->advance(frame);
    ASSERT_TRUE(st.totals.finite) << "frame " << k << ": " << st.totals.bad_stage << " particle "
                                  << st.totals.first_bad;
    EXPECT_LE(st.totals.kinetic_energy + st.totals.elastic_energy, -st.totals.potential_energy * 1.01) << "frame " << k;
  }
  EXPECT_GT(st.totals.stiffening, 10.0);
  EXPECT_GT(st.substeps, 4 * 400);
  EXPECT_GT(st.totals.max_displacement, 0.05);  // it really hangs (the block is 6 cm long)
}

TEST(MlsValidation, PrescribedParticlesReachTheirTargetsAndRelease) {
  // A tool grabs the x = max layer of a bar clamped at x = min and pulls it 1 mm along x over one frame:
  // the grabbed particles land exactly on their targets at the frame's end, the bar stretches (strain energy
  // > 0, interior particles move along +x); after release the layer moves freely again.
  MlsBuildInput in = blockInput(8, 3, 3, 0.01);
  in.material.damping_per_s = 20;
  in.kinds.resize(in.rest_positions.size());
  for (std::size_t i = 0; i < in.kinds.size(); ++i) in.kinds[i] = in.rest_positions[i].x < -0.03 ? kMlsFixed : kMlsFree;
  auto solver = makeMlsSolver(in, BackendKind::Cpu, Precision::Float64);
  const std::vector<Vec3d> rest = solver->restPositions();
  std::vector<std::int32_t> grabbed;
  std::vector<Vec3d> targets;
  for (std::size_t i = 0; i < rest.size(); ++i)
    if (rest[i].x > 0.03) {
      grabbed.push_back(std::int32_t(i));
      targets.push_back(Vec3d(1e-3, 0, 0));
    }
  ASSERT_EQ(grabbed.size(), 9u);
  solver->setPrescribed(grabbed, targets);
  const double frame = 1.0 / 60.0;
  const MlsFrameStats st = solver->advance(frame);
  std::vector<Vec3d> u;
  solver->displacements(u);
  for (const std::int32_t i : grabbed) EXPECT_LT(norm(u[std::size_t(i)] - Vec3d(1e-3, 0, 0)), 1e-15);
  EXPECT_GT(st.totals.elastic_energy, 0.0);
  for (std::size_t i = 0; i < rest.size(); ++i)
    if (std::abs(rest[i].x) < 0.01) {
      EXPECT_GT(u[i].x, 0.0);
    }
  solver->release(grabbed);
  solver->advance(frame);
  solver->displacements(u);
  double moved = 0;
  for (const std::int32_t i : grabbed) moved = std::max(moved, norm(u[std::size_t(i)] - Vec3d(1e-3, 0, 0)));
  EXPECT_GT(moved, 1e-6);  // released: the stretched bar pulls the layer back
  EXPECT_THROW(solver->setPrescribed({std::int32_t(rest.size())}, {Vec3d()}), std::invalid_argument);
}

TEST(MlsValidation, DISABLED_CantileverStudy) {
  // Not part of the suite (slow): tip deflection error against Euler-Bernoulli over support factor and spacing.
  for (const double sf : {1.5, 2.0, 2.5, 3.0})
    for (const int per : {4, 6, 8}) {
      double eb = 0;
      const auto t0 = std::chrono::steady_clock::now();
      const double d = cantileverTipDeflection(0.02 / per, 0.2, 0.02, 5e7, 0.3, 1000, 9.81, eb, sf);
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("support %.1f, %d per thickness: tip %.4e m, EB %.4e m, error %+.1f%% (%.1f s)\n", sf, per, d, eb,
                  100 * (d / eb - 1), s);
    }
}

TEST(MlsValidation, StiffeningUsesTheLargestEigenvalueNotItsBound) {
  // Simple shear F = I + gamma e_x e_y^T: C = F^T F has largest eigenvalue 1 + gamma^2/2 + gamma sqrt(1 + gamma^2/4)
  // (1.6404 for gamma = 0.5), below its Gershgorin bound 1 + gamma + gamma^2 (1.75) that the stiffening used to take.
  MlsCoefficients<double> coeffs;
  coeffs.k_volume = 1.0;  // the volume penalty's c^2 term is the larger one
  const double gamma = 0.5;
  Mat3d g;
  g.m[0][1] = gamma;
  const double c = 1 + 0.5 * gamma * gamma + gamma * std::sqrt(1 + 0.25 * gamma * gamma);
  EXPECT_NEAR(mlsStiffeningOf(g, coeffs), c * c, 1e-9 * c * c);
  EXPECT_LT(mlsStiffeningOf(g, coeffs), std::pow(1 + gamma + gamma * gamma, 2) * 0.9);
  const Mat3f gf(g);
  EXPECT_NEAR(mlsStiffeningOf(gf, MlsCoefficients<float>{0.f, 0.f, 1.f, 0.f}), c * c, 1e-5 * c * c);
}

TEST(MlsValidation, StiffeningWithoutTheVolumePenaltyIsTheSvkTangent) {
  // Volume penalty off, uniaxial stretch F = diag(1.5, 1, 1): C = F^T F has c = 2.25, so the stiffening is SVK's
  // (3 c - 1) / 2 = 2.875 alone (the penalty's c^2 = 5.06 must not enter). Green strain E = diag(0.625, 0, 0),
  // S = diag((2 mu + lambda) E_xx, lambda E_xx, lambda E_xx), P = F S, psi = (mu + lambda / 2) E_xx^2.
  // Checked point-wise and through the stress pass of a block whose every particle sees the same gradient.
  MlsBuildInput in = blockInput(6, 5, 5, 0.01, 0.2);
  ASSERT_FALSE(in.material.volume_preservation);
  MlsModel<double> model = buildMlsModel<double>(in);
  ASSERT_EQ(model.coeffs.k_volume, 0.0);
  const double mu = 1.0e4 / (2 * 1.3), lambda = 1.0e4 * 0.3 / (1.3 * 0.4);  // E = 10 kPa, nu = 0.3
  EXPECT_NEAR(model.coeffs.mu, mu, 1e-12 * mu);
  EXPECT_NEAR(model.coeffs.lambda, lambda, 1e-12 * lambda);  // nothing moved to the (absent) penalty
  const double stretch = 1.5, exx = 0.625, stiffening = 2.875;
  const double psi = (mu + 0.5 * lambda) * exx * exx;
  Mat3d g;
  g.m[0][0] = stretch - 1;
  EXPECT_NEAR(mlsStiffeningOf(g, model.coeffs), stiffening, 1e-12);
  const MlsStressPoint<double> sp = mlsStressPoint(g, model.coeffs);
  const double p_xx = stretch * (2 * mu + lambda) * exx, p_yy = lambda * exx;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      const double want = r != c ? 0.0 : r == 0 ? p_xx : p_yy;
      EXPECT_NEAR(sp.piola.m[r][c], want, 1e-9 * p_xx) << "P(" << r << ", " << c << ")";
    }
  EXPECT_NEAR(sp.energy_density, psi, 1e-12 * psi);

  MlsState<double> state;
  state.resize(model.size());
  std::vector<double> k(model.size(), 0.0);
  MlsView<double> view = makeMlsView(model, state);
  view.stiffening = k.data();
  for (std::size_t i = 0; i < model.size(); ++i) state.displacement[i] = Vec3d((stretch - 1) * model.rest[i].x, 0, 0);
  int regular = 0;
  for (std::int64_t i = 0; i < view.n; ++i) {
    mlsStressPass(view, i);
    if (model.degeneracy[std::size_t(i)] != kMlsRegular) continue;
    ++regular;
    EXPECT_NEAR(k[std::size_t(i)], stiffening, 1e-9) << "particle " << i;
    const double v = model.volume[std::size_t(i)];
    EXPECT_NEAR(state.energy[std::size_t(i)], v * psi, 1e-9 * v * psi) << "particle " << i;
  }
  EXPECT_GT(regular, 0);
}

TEST(MlsValidation, StretchedBodiesTakeSmallerSteps) {
  // A homogeneous stretch F: mlsStiffening = max((3 c - 1)/2, c^2) with c the largest eigenvalue of F^T F
  // (exact for a diagonal F), 1 for a rigid rotation; advance() divides the rest-state limit by its sqrt.
  MlsBuildInput in = blockInput(6, 5, 5, 0.01, 0.2);
  in.material.volume_preservation = true;
  MlsModel<double> model = buildMlsModel<double>(in);
  MlsState<double> state;
  state.resize(model.size());
  const MlsView<double> view = makeMlsView(model, state);
  const Mat3d r = rotation(Vec3d(1, 1, 0), 0.8);
  for (std::size_t i = 0; i < model.size(); ++i) state.displacement[i] = r * model.rest[i] - model.rest[i];
  for (std::int64_t i = 0; i < view.n; ++i)
    if (model.degeneracy[std::size_t(i)] == kMlsRegular) {
      EXPECT_NEAR(mlsStiffening(view, i), 1.0, 1e-12);
    }
  const double stretch = 1.8, c = stretch * stretch;
  for (std::size_t i = 0; i < model.size(); ++i) state.displacement[i] = Vec3d((stretch - 1) * model.rest[i].x, 0, 0);
  for (std::int64_t i = 0; i < view.n; ++i)
    if (model.degeneracy[std::size_t(i)] == kMlsRegular) {
      EXPECT_NEAR(mlsStiffening(view, i), std::max(0.5 * (3 * c - 1), c * c), 1e-10);
    }

  // Released from an 80% stretch, undamped, at the full (safety 1) step: the rest-state step blows up, the
  // guarded plan (rest limit / sqrt(stiffening)) stays finite with the energy within 5%.
  in.material.damping_per_s = 0;
  auto guarded = makeMlsSolver(in, BackendKind::Cpu, Precision::Float64);
  auto unguarded = makeMlsSolver(in, BackendKind::Cpu, Precision::Float64);
  const std::vector<Vec3d> rest = guarded->restPositions();
  std::vector<Vec3d> u(rest.size());
  for (std::size_t i = 0; i < u.size(); ++i) u[i] = Vec3d((stretch - 1) * (rest[i].x - guarded->origin().x), 0, 0);
  guarded->setDisplacements(u);
  unguarded->setDisplacements(u);
  guarded->setSafety(1.0);
  const double e0 = guarded->reduce().total();
  const double frame = 50 * guarded->stableTimeStep();
  bool unguarded_failed = false;
  double worst = 0;
  for (int f = 0; f < 10; ++f) {
    const MlsFrameStats st = guarded->advance(frame);
    ASSERT_TRUE(st.totals.finite) << "frame " << f;
    EXPECT_GE(st.substeps, 50 * std::sqrt(std::max(0.5 * (3 * c - 1), c * c)) * 0.7) << "frame " << f;
    worst = std::max(worst, std::abs(st.totals.total() / e0 - 1));
    unguarded->step(unguarded->stableTimeStep(), 50);
    const MlsReduction ru = unguarded->reduce();
    if (!ru.finite || std::abs(ru.total() / e0 - 1) > 1.0) unguarded_failed = true;
  }
  std::printf("[ MLS ] %.0f%% stretch released at safety 1: guarded energy error %.2e; rest-state step %s\n",
              100 * (stretch - 1), worst, unguarded_failed ? "blew up" : "survived");
  EXPECT_LT(worst, 0.05);
  EXPECT_TRUE(unguarded_failed);  // the guard is needed: the rest-state limit is not enough at this stretch
}

TEST(MlsValidation, UnplannableFrameIsReportedNotThrown) {
  // A state stretched 1e6-fold would need > 1e7 substeps per frame at its stiffness: advance() must not
  // throw (that is physics, not input) but report finite == false at stage "timestep" and leave the state.
  MlsBuildInput in = blockInput(4, 4, 4, 0.01);
  auto solver = makeMlsSolver(in, BackendKind::Cpu, Precision::Float64);
  const std::vector<Vec3d> rest = solver->restPositions();
  std::vector<Vec3d> u(rest.size()), after;
  for (std::size_t i = 0; i < u.size(); ++i) u[i] = Vec3d(1e6 * (rest[i].x - solver->origin().x), 0, 0);
  solver->setDisplacements(u);
  MlsFrameStats st;
  ASSERT_NO_THROW(st = solver->advance(1.0 / 60.0));
  EXPECT_FALSE(st.totals.finite);
  EXPECT_EQ(st.totals.bad_stage, "timestep");
  EXPECT_EQ(st.substeps, 0);
  solver->displacements(after);
  EXPECT_EQ(maxNorm(after), maxNorm(u));
  // Bad input still throws: a non-positive frame.
  EXPECT_THROW(solver->advance(-1.0), InputError);
}

TEST(MlsValidation, TenThousandStepsNearlyIncompressibleUnderGravity) {
  // nu = 0.499, E = 1 MPa, volume penalty on, clamped block sagging under gravity with light damping: 10^4
  // substeps, every frame finite, kinetic + strain energy never above the work of gravity, volume kept.
  MlsBuildInput in = blockInput(6, 3, 3, 0.01, 0.2);
  in.material.poisson_ratio = 0.499;
  in.material.youngs_modulus_pa = 1e6;
  in.material.volume_preservation = true;
  in.material.damping_per_s = 2.0;
  in.gravity = Vec3d(0, 0, -9.81);
  in.kinds.resize(in.rest_positions.size());
  for (std::size_t i = 0; i < in.kinds.size(); ++i) in.kinds[i] = in.rest_positions[i].x < -0.02 ? kMlsFixed : kMlsFree;
  auto solver = makeMlsSolver(in, BackendKind::Cpu, Precision::Float32);
  const double frame = 500 * solver->safety() * solver->stableTimeStep();
  int steps = 0;
  MlsFrameStats st;
  while (steps < 10000) {
    st = solver->advance(frame);
    steps += st.substeps;
    ASSERT_TRUE(st.totals.finite) << "after " << steps << " steps";
    EXPECT_LE(st.totals.kinetic_energy + st.totals.elastic_energy, -st.totals.potential_energy * 1.01 + 1e-15);
  }
  EXPECT_GT(st.totals.max_displacement, 0.0);
  EXPECT_LT(st.totals.max_displacement, 1e-3);  // 1 MPa: a sub-millimetre sag
}
