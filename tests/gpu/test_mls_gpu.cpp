// MLS solver on the GPU: CPU == GPU parity after 100 steps, determinism, frame reductions, failure reporting.
#if INCISION_HAVE_CUDA
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "host/backends/solver_factory.h"
#include "host/scene/scene_compile.h"
#include "host/sim/mls_simulation.h"
#include "kernels/device_info.h"
#include "model/mls_solver.h"
#include "tests/support/mls_test_scenes.h"

using namespace inc;
using namespace inc::mls_test;

namespace {

bool noDevice() { return inc::cuda::queryDevices().device_count == 0; }

// A jittered 12 x 6 x 6 block clamped at x = min, sagging under gravity, started from a smooth 1% strain.
MlsBuildInput parityInput() {
  MlsBuildInput in = blockInput(12, 6, 6, 0.005, 0.2);
  in.material.volume_preservation = true;
  in.material.damping_per_s = 2.0;
  in.gravity = Vec3d(0, 0, -9.81);
  in.kinds.resize(in.rest_positions.size());
  for (std::size_t i = 0; i < in.kinds.size(); ++i)
    in.kinds[i] = in.rest_positions[i].x < -0.025 ? kMlsFixed : kMlsFree;
  return in;
}

std::vector<Vec3d> initialField(const MlsSolver& s) {
  const std::vector<Vec3d> rest = s.restPositions();
  std::vector<Vec3d> u(rest.size());
  for (std::size_t i = 0; i < u.size(); ++i) {
    const Vec3d x = rest[i] - s.origin();
    u[i] = Vec3d(0.01 * x.x, -0.004 * x.y + 0.1 * x.x * x.x, 0.003 * x.z);
  }
  return u;
}

double maxDiff(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, norm(a[i] - b[i]));
  return m;
}

}  // namespace

TEST(MlsGpu, CpuAndGpuAgreeAfter100Steps) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  // Tolerance relative to the largest displacement: float64 1e-10, float32 1e-5 (same header math on both;
  // only FMA contraction and rounding order differ).
  for (const Precision prec : {Precision::Float64, Precision::Float32}) {
    const MlsBuildInput in = parityInput();
    auto cpu = makeMlsSolver(in, BackendKind::Cpu, prec);
    auto gpu = makeMlsSolver(in, BackendKind::Cuda, prec);
    ASSERT_EQ(gpu->backend(), BackendKind::Cuda);
    ASSERT_EQ(cpu->size(), gpu->size());
    const std::vector<Vec3d> u0 = initialField(*cpu);
    cpu->setDisplacements(u0);
    gpu->setDisplacements(u0);
    // Forces at the same state first.
    cpu->computeForces();
    gpu->computeForces();
    std::vector<Vec3d> fc, fg;
    cpu->forces(fc);
    gpu->forces(fg);
    const double tol = prec == Precision::Float64 ? 1e-10 : 1e-5;
    EXPECT_LT(maxDiff(fc, fg) / maxNorm(fc), tol) << precisionName(prec) << " forces";
    const double dt = cpu->safety() * cpu->stableTimeStep();
    cpu->step(dt, 100);
    gpu->step(dt, 100);
    std::vector<Vec3d> uc, ug, vc, vg;
    cpu->displacements(uc);
    gpu->displacements(ug);
    cpu->velocities(vc);
    gpu->velocities(vg);
    EXPECT_LT(maxDiff(uc, ug) / maxNorm(uc), tol) << precisionName(prec) << " displacements";
    EXPECT_LT(maxDiff(vc, vg) / maxNorm(vc), 10 * tol) << precisionName(prec) << " velocities";
    const MlsReduction rc = cpu->reduce(), rg = gpu->reduce();
    EXPECT_TRUE(rg.finite);
    EXPECT_NEAR(rg.kinetic_energy / rc.kinetic_energy, 1.0, 100 * tol);
    EXPECT_NEAR(rg.elastic_energy / rc.elastic_energy, 1.0, 100 * tol);
    EXPECT_NEAR(rg.potential_energy / rc.potential_energy, 1.0, 100 * tol);
    EXPECT_NEAR(rg.max_displacement / rc.max_displacement, 1.0, 10 * tol);
  }
}

TEST(MlsGpu, RunsAreBitwiseDeterministic) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  const MlsBuildInput in = parityInput();
  std::vector<Vec3d> first, second;
  double e_first = 0, e_second = 0;
  for (int run = 0; run < 2; ++run) {
    auto gpu = makeMlsSolver(in, BackendKind::Cuda, Precision::Float32);
    gpu->setDisplacements(initialField(*gpu));
    const MlsFrameStats st = gpu->advance(1.0 / 60.0);
    gpu->displacements(run == 0 ? first : second);
    (run == 0 ? e_first : e_second) = st.totals.total();
  }
  EXPECT_EQ(maxDiff(first, second), 0.0);
  EXPECT_EQ(e_first, e_second);
}

TEST(MlsGpu, NonFiniteStateIsReportedWithParticleAndStage) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  // A NaN displacement at particle 37 spreads to its neighbours' forces; both backends report the same
  // lowest bad particle and stage.
  const MlsBuildInput in = parityInput();
  auto gpu = makeMlsSolver(in, BackendKind::Cuda, Precision::Float32);
  auto cpu = makeMlsSolver(in, BackendKind::Cpu, Precision::Float32);
  std::vector<Vec3d> u(gpu->size());
  u[37].y = std::numeric_limits<double>::quiet_NaN();
  gpu->setDisplacements(u);
  cpu->setDisplacements(u);
  const MlsReduction rg = gpu->reduce(), rc = cpu->reduce();
  EXPECT_FALSE(rg.finite);
  EXPECT_GE(rg.first_bad, 0);
  EXPECT_LE(rg.first_bad, 37);
  EXPECT_EQ(rg.first_bad, rc.first_bad);
  EXPECT_EQ(rg.bad_stage, rc.bad_stage);
}

TEST(MlsGpu, PrescribedParticlesMatchTheCpu) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  // The x = max layer is pulled 2 mm along +x and 1 mm down over a frame, then released for another frame.
  const MlsBuildInput in = parityInput();
  auto cpu = makeMlsSolver(in, BackendKind::Cpu, Precision::Float64);
  auto gpu = makeMlsSolver(in, BackendKind::Cuda, Precision::Float64);
  const std::vector<Vec3d> rest = cpu->restPositions();
  double xmax = -1e30;
  for (const auto& x : rest) xmax = std::max(xmax, x.x);
  std::vector<std::int32_t> grabbed;
  for (std::size_t i = 0; i < rest.size(); ++i)
    if (rest[i].x > xmax - 0.004) grabbed.push_back(std::int32_t(i));
  const std::vector<Vec3d> targets(grabbed.size(), Vec3d(2e-3, 0, -1e-3));
  cpu->setPrescribed(grabbed, targets);
  gpu->setPrescribed(grabbed, targets);
  cpu->advance(1.0 / 60.0);
  gpu->advance(1.0 / 60.0);
  std::vector<Vec3d> uc, ug;
  gpu->displacements(ug);
  for (const std::int32_t i : grabbed) EXPECT_LT(norm(ug[std::size_t(i)] - targets[0]), 1e-12);
  cpu->release(grabbed);
  gpu->release(grabbed);
  cpu->advance(1.0 / 60.0);
  gpu->advance(1.0 / 60.0);
  cpu->displacements(uc);
  gpu->displacements(ug);
  EXPECT_LT(maxDiff(uc, ug) / maxNorm(uc), 1e-10);
}

// The parity block, unclamped, dropped onto a floor tilted 0.3 rad about x (friction 0.4) and against a box at its
// side (friction 0.2): the static contacts run in the same drift on both backends (physics/mls_static_contact.h).
TEST(MlsGpu, StaticCollidersMatchTheCpu) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  MlsBuildInput in = parityInput();
  in.kinds.clear();
  in.gravity = Vec3d(1.0, 0, -30.0);
  auto cpu = makeMlsSolver(in, BackendKind::Cpu, Precision::Float64);
  auto gpu = makeMlsSolver(in, BackendKind::Cuda, Precision::Float64);
  const Vec3d n(0, std::sin(0.3), std::cos(0.3));
  double low = 1e30, high = -1e30;
  for (const Vec3d& x : cpu->restPositions()) low = std::min(low, dot(n, x)), high = std::max(high, x.x);
  const std::vector<pbd::PlaneCollider<double>> planes{{n, low - 0.004, 0.4}};
  const std::vector<pbd::BoxCollider<double>> boxes{{Vec3d(high + 0.003, -1, -1), Vec3d(high + 0.05, 1, 1), 0.2}};
  cpu->setStaticColliders(planes, boxes, 0.002);
  gpu->setStaticColliders(planes, boxes, 0.002);
  std::vector<Vec3d> xc, xg;
  double min_gap = 1e30;
  for (int f = 0; f < 20; ++f) {
    cpu->advance(1.0 / 60.0);
    gpu->advance(1.0 / 60.0);
    gpu->positions(xg);
    for (const Vec3d& x : xg) min_gap = std::min(min_gap, dot(n, x) - (low - 0.004));
  }
  cpu->positions(xc);
  std::vector<Vec3d> uc, ug;
  cpu->displacements(uc);
  gpu->displacements(ug);
  EXPECT_GE(min_gap, 0.002 - 1e-12);  // the points are balls of 2 mm
  EXPECT_LT(min_gap, 0.002 + 1e-4) << "the block reaches the floor";
  EXPECT_LT(maxDiff(uc, ug) / maxNorm(uc), 1e-9);
}

TEST(MlsGpu, SimulationRunsTheBeamSceneOnTheDevice) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  Scene s;
  s.file = "<gpu beam>";
  s.geometry.kind = GeometrySpec::Kind::Beam;
  s.geometry.center = Vec3d(0.04, 0, 0);
  s.geometry.size = Vec3d(0.08, 0.02, 0.02);
  s.geometry.spacing = 0.0025;
  s.material.youngs_modulus_pa = 2e5;
  s.material.poisson_ratio = 0.4;
  s.material.damping_per_s = 10;
  s.models.mls = true;
  FixedRegion clamp;
  clamp.min = Vec3d(-0.001, -0.011, -0.011);
  clamp.max = Vec3d(0.0051, 0.011, 0.011);
  s.fixed.push_back(clamp);
  auto gpu = makeMlsSimulation(compileScene(s), BackendKind::Cuda, Precision::Float32);
  auto cpu = makeMlsSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  FrameReport rg, rc;
  for (int f = 0; f < 3; ++f) {
    rg = gpu->advance(s.solver.frame_dt);
    rc = cpu->advance(s.solver.frame_dt);
  }
  EXPECT_TRUE(rg.finite);
  EXPECT_LE(std::abs(rg.substeps - rc.substeps), 1);  // planned from each backend's own stiffening (rounding)
  EXPECT_NEAR(rg.max_displacement / rc.max_displacement, 1.0, 1e-4);
  EXPECT_NEAR(rg.elastic_energy / rc.elastic_energy, 1.0, 1e-3);
  double stage_ms = 0;
  for (const auto& st : rg.stages) stage_ms += st.ms;
  EXPECT_GT(stage_ms, 0.0);
  EXPECT_GT(gpu->memory().device_bytes, 0u);
}

#endif  // INCISION_HAVE_CUDA
