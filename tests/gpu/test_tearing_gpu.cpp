// GPU tearing step against the CPU fallback: identical yield sets, accepted sets and topology for the same seed.
#include <gtest/gtest.h>

#if INCISION_HAVE_CUDA

#include <random>

#include "cpu_fallback/tearing_cpu.h"
#include "host/tear/tearing_driver.h"
#include "kernels/device_info.h"
#include "kernels/tearing_cuda.h"
#include "model/tearing_sheet.h"

using namespace inc;

namespace {

bool haveDevice() { return inc::cuda::queryDevices().device_count > 0; }

// Jiggled sheet: positions off any symmetric configuration, so no side test sits exactly on a tie.
template <typename T>
TearSheet<T> jiggled(int n, std::uint32_t seed, double amp) {
  TearSheet<T> s = makeTearGrid<T>(n, n, 0.01, 2.2, Vec3d(0, 0, 0), 1.0e4, 120.0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  for (std::size_t i = 0; i < s.size(); ++i) {
    s.x[i] = s.rest[i] + Vec3<T>(Vec3d(u(rng), u(rng), u(rng)) * (amp * 0.01));
    s.v[i] = Vec3<T>(Vec3d(u(rng), u(rng), u(rng)));
  }
  return s;
}

template <typename T>
void expectSameStep(TearCriterion crit, double pos_tol) {
  for (std::uint32_t trial = 0; trial < 3; ++trial) {
    TearSheet<T> a = jiggled<T>(60, 100 + trial, 0.12), b = a;
    TearParams<T> p;
    p.criterion = crit;
    p.break_strain = T(0.12);
    p.seed = 7 + trial;
    TearCandidates<T> ca, cb;
    const TearStepStats sa = cpu::tearStepCpu(a, p, &ca);
    const TearStepStats sb = cuda::tearStepCuda(b, p, &cb);
    b.rebuildTopology();
    EXPECT_GT(sa.splits, 50);
    EXPECT_EQ(sa.splits, sb.splits);
    EXPECT_EQ(sa.yielding, sb.yielding);
    EXPECT_EQ(ca.yield, cb.yield);
    EXPECT_EQ(ca.accept, cb.accept);
    EXPECT_EQ(ca.partner, cb.partner);
    EXPECT_EQ(a.tris, b.tris) << "identical topology for the same seed";
    ASSERT_EQ(a.size(), b.size());
    double err = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      err = std::max(err, double(norm(a.x[i] - b.x[i])) + double(norm(a.rest[i] - b.rest[i])));
      EXPECT_EQ(a.fixed[i], b.fixed[i]);
    }
    EXPECT_LT(err, pos_tol);  // m: FMA contraction on the device differs in the last bits only
    EXPECT_EQ(a.edge_a, b.edge_a);
  }
}

}  // namespace

TEST(TearingGpu, TrescaStepMatchesCpuDouble) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  expectSameStep<double>(TearCriterion::TrescaBonds, 1e-12);
}

TEST(TearingGpu, TraditionalAndPrincipalMatchCpuDouble) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  expectSameStep<double>(TearCriterion::Threshold, 1e-12);
  expectSameStep<double>(TearCriterion::TrescaPrincipal, 1e-12);
}

TEST(TearingGpu, TrescaStepMatchesCpuFloat) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  expectSameStep<float>(TearCriterion::TrescaBonds, 1e-6);
}

TEST(TearingGpu, ManyStepsSameTopologyAndValidMesh) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  TearSheet<double> a = jiggled<double>(50, 3, 0.0), b = a;
  TearParams<double> p;
  p.seed = 21;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  int total = 0;
  for (int step = 0; step < 10; ++step) {
    for (std::size_t i = 0; i < a.size(); ++i) {
      a.x[i] = a.rest[i] + Vec3d(u(rng), u(rng), u(rng)) * 0.0012;
      b.x[i] = a.x[i];
    }
    total += cpu::tearStepCpu(a, p).splits;
    if (cuda::tearStepCuda(b, p).splits > 0) b.rebuildTopology();
    ASSERT_EQ(a.tris, b.tris) << "step " << step;
    for (std::size_t i = 0; i < a.size(); ++i) b.x[i] = a.x[i];  // keep the next jiggle identical
  }
  EXPECT_GT(total, 1000);
  EXPECT_TRUE(checkTearMesh(b).valid());
}

TEST(TearingGpu, DriverRunsOnCuda) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  TearSheet<float> s = makeTearGrid<float>(30, 15, 0.01, 2.2, Vec3d(0, 0, 0), 1.0e4, 150.0);
  fixTearParticles(s, Vec3d(-1, -1, -1), Vec3d(1e-3, 1, 1));
  std::vector<std::int32_t> grasp;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.rest[i].x > 0.289f) grasp.push_back(std::int32_t(i));
  PbdStepParams<float> sp;
  sp.gravity = Vec3f(0, 0, 0);
  sp.volume_preservation = false;
  TearModelOptions mo;
  mo.stretch_compliance = 2e-4;
  mo.bending_compliance = 10;
  TearingDriver<float> d(s, TearParams<float>(), mo, sp, BackendKind::Cuda);
  EXPECT_EQ(d.kind(), BackendKind::Cuda);
  int splits = 0;
  for (int f = 0; f < 20; ++f) {
    std::vector<Vec3f> to;
    for (std::int32_t id : grasp) to.push_back(d.sheet().rest[id] + Vec3f(0.01f * float(f + 1), 0, 0));
    splits += d.advance(grasp, to).splits;
  }
  EXPECT_GT(splits, 0);
  EXPECT_TRUE(checkTearMesh(d.sheet()).valid());
}

#endif  // INCISION_HAVE_CUDA
