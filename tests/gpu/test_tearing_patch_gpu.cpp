// PBD CUDA patch API and the device-resident tearing path: patched device model == host rebuild of the same topology.
#include <gtest/gtest.h>

#if INCISION_HAVE_CUDA

#include <algorithm>
#include <array>
#include <random>
#include <tuple>

#include "cpu_fallback/tearing_cpu.h"
#include "host/backends/solver_factory.h"
#include "host/scene/scene_compile.h"
#include "host/sim/tearing_simulation.h"
#include "host/tear/tearing_driver.h"
#include "kernels/cuda_check.h"
#include "kernels/device_info.h"
#include "kernels/pbd_device_cuda.h"
#include "kernels/pbd_solver_cuda.h"
#include "kernels/tearing_cuda.h"
#include "model/tearing_sheet.h"

using namespace inc;

namespace {

bool haveDevice() { return inc::cuda::queryDevices().device_count > 0; }

TearModelOptions jacobiOptions() {
  TearModelOptions o;
  o.stretch_compliance = 2e-4;
  o.bending_compliance = 10.0;
  o.coloring = false;
  return o;
}

// A sheet before and after a few CPU tearing steps (the same particles first, then the new ones).
template <typename T>
void sheetPair(TearSheet<T>& before, TearSheet<T>& after) {
  before = makeTearGrid<T>(24, 20, 0.01, 2.2, Vec3d(0, 0, 0), 1.0e4, 120.0);
  fixTearParticles(before, Vec3d(-1, -1, -1), Vec3d(1, 0.005, 1));
  after = before;
  TearParams<T> p;
  p.seed = 3;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 3; ++k) {
    for (std::size_t i = 0; i < after.size(); ++i)
      after.x[i] = after.rest[i] + Vec3<T>(Vec3d(u(rng), u(rng), u(rng)) * 0.0012);
    cpu::tearStepCpu(after, p);
  }
  after.x = after.rest;  // start the solve from rest
  for (auto& v : after.v) v = Vec3<T>();
}

// Constraint tuples (sorted ids of the constraint as given, then the rest value) in ascending order.
template <typename T>
std::vector<std::pair<std::array<std::int32_t, 4>, double>> tuples(const PbdConstraintBlock<T>& b) {
  std::vector<std::pair<std::array<std::int32_t, 4>, double>> out;
  for (std::size_t c = 0; c < b.count(); ++c) {
    std::array<std::int32_t, 4> id{-1, -1, -1, -1};
    for (std::int32_t q = b.offsets[c]; q < b.offsets[c + 1]; ++q) id[std::size_t(q - b.offsets[c])] = b.ids[q];
    out.push_back({id, double(b.rest[c])});
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The device block against the host block: the same constraints as sorted tuples (rest within rest_tol), and
// with the same construction order the same arrays (incidence and Jacobi scales exactly).
template <typename T>
void expectBlockEqual(const PbdConstraintBlock<T>& dev, const PbdConstraintBlock<T>& host, double rest_tol,
                      const char* what) {
  const auto a = tuples(dev), b = tuples(host);
  ASSERT_EQ(a.size(), b.size()) << what;
  double err = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].first, b[k].first) << what << " constraint " << k;
    err = std::max(err, std::abs(a[k].second - b[k].second));
  }
  EXPECT_LE(err, rest_tol) << what;
  EXPECT_EQ(dev.ids, host.ids) << what << ": construction order";
  EXPECT_EQ(dev.offsets, host.offsets) << what;
  EXPECT_EQ(dev.particle_offsets, host.particle_offsets) << what;
  EXPECT_EQ(dev.particle_slots, host.particle_slots) << what;
  EXPECT_EQ(dev.jacobi_scale, host.jacobi_scale) << what;
  EXPECT_EQ(dev.compliance, host.compliance) << what;
}

PbdStepParams<double> jacobiStep() {
  PbdStepParams<double> sp;
  sp.gravity = Vec3d(0, 0, -9.81);
  sp.volume_preservation = false;
  sp.solver = PbdSolverKind::Jacobi;
  return sp;
}

}  // namespace

// Patch API: a model patched in place (particles appended, blocks rewritten from the host) equals a fresh
// setModel of the torn topology: same device arrays and, over frames, the same positions.
TEST(PbdPatchGpu, AppendAndCommitEqualHostModel) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  TearSheet<double> a, b;
  sheetPair(a, b);
  ASSERT_GT(b.size(), a.size() + 50) << "the torn sheet must have new particles";
  const PbdModel<double> ma = buildTearPbdModel(a, jacobiOptions()), mb = buildTearPbdModel(b, jacobiOptions());
  ASSERT_EQ(mb.blocks.size(), 2u);
  auto patched = cuda::makePbdCudaBackend<double>();
  auto fresh = cuda::makePbdCudaBackend<double>();
  patched->setModel(ma);
  fresh->setModel(mb);
  cuda::PbdDevicePatch<double>* patch = cuda::pbdDevicePatch<double>(*patched);
  ASSERT_NE(patch, nullptr);
  patch->appendParticlesFromHost(b.rest, b.x, b.v, b.mass, b.fixed);
  EXPECT_EQ(patch->deviceParticles().n, int(b.size()));
  for (int k = 0; k < 2; ++k)
    patch->setBlockFromHost(k, mb.blocks[std::size_t(k)].ids, mb.blocks[std::size_t(k)].rest,
                            mb.blocks[std::size_t(k)].compliance);
  EXPECT_EQ(patch->downloadInverseMasses(), mb.inv_mass);  // IEEE division on both sides
  for (int k = 0; k < 2; ++k)
    expectBlockEqual(patch->downloadBlock(k), mb.blocks[std::size_t(k)], 0.0, "patched block");

  PbdState<double> s0;
  s0.positions = b.x;
  s0.velocities = b.v;
  s0.radii.assign(b.size(), 0.0);
  s0.rotations.assign(b.size(), pbd::Quat<double>{});
  patched->setState(s0);
  fresh->setState(s0);
  PbdFrameInput<double> in;  // pull a corner kinematically
  in.kinematic_ids = {std::int32_t(a.size()) - 1};
  in.kinematic_from = {b.x[a.size() - 1]};
  const PbdStepParams<double> sp = jacobiStep();
  for (int f = 0; f < 6; ++f) {
    in.kinematic_to = {in.kinematic_from[0] + Vec3d(0.002, 0, 0.001)};
    const PbdFrameStats ra = patched->advanceFrame(sp, in), rb = fresh->advanceFrame(sp, in);
    EXPECT_TRUE(ra.finite && rb.finite);
    in.kinematic_from = in.kinematic_to;
  }
  PbdState<double> sa, sb;
  patched->getState(sa);
  fresh->getState(sb);
  ASSERT_EQ(sa.positions.size(), sb.positions.size());
  double err = 0, moved = 0;
  for (std::size_t i = 0; i < sa.positions.size(); ++i) {
    err = std::max(err, norm(sa.positions[i] - sb.positions[i]));
    moved = std::max(moved, norm(sb.positions[i] - b.x[i]));
  }
  EXPECT_GT(moved, 1e-3) << "the frames must move the sheet";
  EXPECT_LE(err, 1e-12) << "m: identical arrays, identical gather order";
  // A patched model has no colouring: Gauss-Seidel is refused, not silently wrong.
  PbdStepParams<double> gs = sp;
  gs.solver = PbdSolverKind::GaussSeidel;
  EXPECT_THROW(patched->advanceFrame(gs, PbdFrameInput<double>()), InputError);
}

// commitBlockIncidence: the caller's particle -> slot CSR (here the host model's, uploaded) is taken as given
// and the rest (offsets, Jacobi scales, multipliers) is what commitBlock computes: the same device block.
TEST(PbdPatchGpu, CommitWithCallerIncidenceEqualsHostModel) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  TearSheet<double> a, b;
  sheetPair(a, b);
  const PbdModel<double> ma = buildTearPbdModel(a, jacobiOptions()), mb = buildTearPbdModel(b, jacobiOptions());
  ASSERT_EQ(mb.blocks.size(), 2u);
  auto backend = cuda::makePbdCudaBackend<double>();
  backend->setModel(ma);
  cuda::PbdDevicePatch<double>* patch = cuda::pbdDevicePatch<double>(*backend);
  ASSERT_NE(patch, nullptr);
  patch->appendParticlesFromHost(b.rest, b.x, b.v, b.mass, b.fixed);
  for (int k = 0; k < 2; ++k) {
    const PbdConstraintBlock<double>& h = mb.blocks[std::size_t(k)];
    const cuda::PbdDeviceBlock<double> r = patch->reserveBlock(k, h.count());
    const cuda::PbdDeviceIncidence inc = patch->reserveIncidence(k, h.count());
    ASSERT_GE(inc.slot_capacity, h.particle_slots.size());
    ASSERT_EQ(cudaDeviceSynchronize(), cudaSuccess);
    auto up = [](void* dst, const auto& v) {
      ASSERT_EQ(cudaMemcpy(dst, v.data(), v.size() * sizeof(v[0]), cudaMemcpyHostToDevice), cudaSuccess);
    };
    up(r.ids, h.ids);
    up(r.rest, h.rest);
    up(r.compliance, h.compliance);
    up(inc.particle_offsets, h.particle_offsets);
    up(inc.particle_slots, h.particle_slots);
    patch->commitBlockIncidence(k, int(h.count()));
    expectBlockEqual(patch->downloadBlock(k), h, 0.0, "caller incidence");
  }
  EXPECT_THROW(patch->commitBlockIncidence(0, 1 << 30), InputError);  // beyond the reserved constraints
}

TEST(PbdPatchGpu, GrowsBeyondCapacityAndRefusesBadInput) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  TearSheet<float> a, b;
  sheetPair(a, b);
  const PbdModel<float> ma = buildTearPbdModel(a, jacobiOptions());
  auto backend = cuda::makePbdCudaBackend<float>();
  backend->setModel(ma);
  cuda::PbdDevicePatch<float>* patch = cuda::pbdDevicePatch<float>(*backend);
  ASSERT_NE(patch, nullptr);
  const std::size_t cap0 = patch->deviceParticles().capacity;
  patch->reserveParticles(4 * cap0);  // geometric growth, live prefix kept
  EXPECT_GE(patch->deviceParticles().capacity, 4 * cap0);
  EXPECT_EQ(patch->downloadInverseMasses(), ma.inv_mass);
  EXPECT_EQ(patch->downloadBlock(0).ids, ma.blocks[0].ids);
  const int beyond = int(patch->deviceParticles().capacity) + 1;
  EXPECT_THROW(patch->appendParticles(beyond, nullptr), InputError);  // beyond capacity: refused before any launch
  EXPECT_THROW(patch->setBlockFromHost(0, {0, 1, 2}, {0.01f}, {0.0f}), InputError);    // wrong arity
  EXPECT_THROW(patch->setBlockFromHost(0, {0, 100000}, {0.01f}, {0.0f}), InputError);  // index out of range
  EXPECT_THROW(patch->commitBlock(0, 1 << 30), InputError);  // beyond the reserved constraints
  EXPECT_THROW(patch->setSummaryEvery(0), InputError);
  auto cpu = makePbdBackend<float>(BackendKind::Cpu);
  EXPECT_EQ(cuda::pbdDevicePatch<float>(*cpu), nullptr);
}

namespace {

template <typename T>
TearingDriver<T> pulledDriver(bool resident, TearCriterion crit, bool graph = true) {
  TearSheet<T> s = makeTearGrid<T>(40, 20, 0.01, 2.2, Vec3d(0, 0, 0), 1.0e4, 150.0);
  fixTearParticles(s, Vec3d(-1, -1, -1), Vec3d(1e-3, 1, 1));
  PbdStepParams<T> sp;
  sp.gravity = Vec3<T>(0, 0, 0);
  sp.volume_preservation = false;
  sp.solver = PbdSolverKind::Jacobi;
  sp.use_graph = graph;
  TearModelOptions mo;
  mo.stretch_compliance = 2e-4;
  mo.bending_compliance = 10;
  TearParams<T> tp;
  tp.criterion = crit;
  tp.break_strain = T(0.15);  // traditional: breaks within the pull as Tresca does
  tp.seed = 5;
  TearingDriver<T> d(s, tp, mo, sp, BackendKind::Cuda);
  if (!resident) {
    d.allow_device_resident = false;
    d.resetModel();
  }
  return d;
}

template <typename T>
int pull(TearingDriver<T>& d, int frames) {
  std::vector<std::int32_t> grasp;
  std::vector<Vec3<T>> base;
  const TearSheet<T>& s = d.sheet();
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.rest[i].x > T(0.389)) {
      grasp.push_back(std::int32_t(i));
      base.push_back(s.rest[i]);
    }
  int splits = 0;
  for (int f = 0; f < frames; ++f) {
    std::vector<Vec3<T>> to;
    for (const Vec3<T>& b : base) to.push_back(b + Vec3<T>(T(0.012) * T(f + 1), T(0.002) * T(f % 3), 0));
    splits += d.advance(grasp, to).splits;
  }
  return splits;
}

}  // namespace

// The brief's parity: after N tearing frames on the device-resident path, the PBD model on the device equals a
// fresh host rebuild (buildTearPbdModel) of the downloaded topology, compared as sorted tuples and array for array.
TEST(TearingPatchGpu, ResidentModelEqualsHostRebuildAfterTearing) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  for (TearCriterion crit : {TearCriterion::TrescaBonds, TearCriterion::Threshold}) {
    TearingDriver<float> d = pulledDriver<float>(true, crit);
    ASSERT_TRUE(d.deviceResident());
    const int splits = pull(d, 16);
    EXPECT_GT(splits, 10) << tearCriterionName(crit) << ": the pull must tear";
    const TearSheet<float>& s = d.sheet();  // downloaded, adjacency rebuilt on the host
    EXPECT_EQ(s.size(), d.particleCount());
    EXPECT_TRUE(checkTearMesh(s).valid()) << tearCriterionName(crit);
    TearModelOptions mo = jacobiOptions();
    const PbdModel<float> host = buildTearPbdModel(s, mo);
    cuda::PbdDevicePatch<float>* patch = cuda::pbdDevicePatch<float>(d.pbdBackend());
    ASSERT_NE(patch, nullptr);
    ASSERT_EQ(host.blocks.size(), 2u);
    // rest values: the device evaluates the same expressions (FMA contraction may differ in the last bits)
    expectBlockEqual(patch->downloadBlock(0), host.blocks[0], 2e-8, "distance");
    expectBlockEqual(patch->downloadBlock(1), host.blocks[1], 2e-6, "bending");
    const std::vector<float> w = patch->downloadInverseMasses();
    ASSERT_EQ(w.size(), host.inv_mass.size());
    for (std::size_t i = 0; i < w.size(); ++i) ASSERT_EQ(w[i], host.inv_mass[i]) << "particle " << i;
  }
}

// Same scene on CUDA: device-resident path vs the host path (host sheet, host rebuild, setModel each tearing
// frame). The solve kernels and (array for array) the models are the same, so the debris is the same.
TEST(TearingPatchGpu, ResidentPathSameTopologyAsHostPath) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  TearingDriver<double> res = pulledDriver<double>(true, TearCriterion::TrescaBonds);
  TearingDriver<double> host = pulledDriver<double>(false, TearCriterion::TrescaBonds);
  ASSERT_TRUE(res.deviceResident());
  ASSERT_FALSE(host.deviceResident());
  const double m0 = totalMass(res.sheet());
  const int sa = pull(res, 12), sb = pull(host, 12);
  EXPECT_GT(sa, 20);
  EXPECT_EQ(sa, sb);
  EXPECT_EQ(res.sheet().tris, host.sheet().tris) << "same seed, same debris";
  ASSERT_EQ(res.sheet().size(), host.sheet().size());
  double err = 0;
  for (std::size_t i = 0; i < res.sheet().size(); ++i) err = std::max(err, norm(res.sheet().x[i] - host.sheet().x[i]));
  // Same kernels, same topology; the two paths differ only in where rest values and split positions are
  // evaluated (device vs host: FMA contraction differs in the last bits), and 12 frames of a 144 mm pull at
  // the yield point amplify that. Measured 6.4e-7 m on the H100 (2026-11-25); 1e-5 m is 7e-5 of the pull.
  EXPECT_LT(err, 1e-5) << "m";
  EXPECT_NEAR(totalMass(res.sheet()), m0, 1e-12 * m0) << "splits conserve mass";
  // Removal (a host edit) and further tearing frames keep working on the resident path.
  std::vector<std::uint8_t> mark(res.particleCount(), 0);
  mark[res.particleCount() - 1] = 1;
  EXPECT_GE(res.removeParticles(mark), 1);
  EXPECT_TRUE(res.deviceResident());
  pull(res, 2);
  EXPECT_TRUE(checkTearMesh(res.sheet()).valid());
}

// A patch changes only counts, which the frame's kernels read on the device: the captured graph is kept across
// tearing frames (re-captured only when a grid bucket changes) and gives the frames of direct launches bit for bit.
// A graph that kept a stale count would leave the new constraints unsolved and move the sheet differently.
TEST(TearingPatchGpu, GraphKeptAcrossPatchesEqualsDirectLaunches) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  TearingDriver<float> g = pulledDriver<float>(true, TearCriterion::TrescaBonds, true);
  TearingDriver<float> d = pulledDriver<float>(true, TearCriterion::TrescaBonds, false);
  const int sg = pull(g, 12), sd = pull(d, 12);
  EXPECT_GT(sg, 20);
  EXPECT_EQ(sg, sd);
  EXPECT_EQ(g.sheet().tris, d.sheet().tris);
  ASSERT_EQ(g.sheet().size(), d.sheet().size());
  for (std::size_t i = 0; i < g.sheet().size(); ++i) {
    ASSERT_EQ(g.sheet().x[i].x, d.sheet().x[i].x) << i;
    ASSERT_EQ(g.sheet().x[i].y, d.sheet().x[i].y) << i;
    ASSERT_EQ(g.sheet().x[i].z, d.sheet().x[i].z) << i;
  }
}

TEST(TearingPatchGpu, GaussSeidelKeepsTheHostPath) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  TearSheet<float> s = makeTearGrid<float>(20, 10, 0.01, 2.2, Vec3d(0, 0, 0), 1.0e4, 150.0);
  PbdStepParams<float> sp;
  sp.solver = PbdSolverKind::GaussSeidel;
  sp.volume_preservation = false;
  TearingDriver<float> d(s, TearParams<float>(), TearModelOptions(), sp, BackendKind::Cuda);
  EXPECT_FALSE(d.deviceResident());
  const TearFrameStats st = d.advance({}, {});
  EXPECT_FALSE(st.device_resident);
  EXPECT_TRUE(st.pbd.finite);
}

// CPU tearing step vs the device-resident step fed the same jiggled positions for 10 steps (> 1000 splits):
// the same topology for the same seed, and the patched device model equal to a host rebuild of it, with the
// per-particle device rebuild (the default) and with the radix-sort one.
TEST(TearingPatchGpu, ResidentStepsMatchCpuStepsForTheSameSeed) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  for (const bool sorted : {false, true}) {
    SCOPED_TRACE(sorted ? "radix-sort rebuild" : "per-particle rebuild");
    TearSheet<double> a = makeTearGrid<double>(50, 50, 0.01, 2.2, Vec3d(0, 0, 0), 1.0e4, 120.0);
    fixTearParticles(a, Vec3d(-1, -1, -1), Vec3d(1, 0.005, 1));
    TearModelOptions mo = jacobiOptions();
    mo.device_sorted_rebuild = sorted;
    auto pbd = cuda::makePbdCudaBackend<double>();
    pbd->setModel(buildTearPbdModel(a, mo));
    auto tb = cuda::makeTearStepCuda<double>();
    ASSERT_TRUE(tb->attach(*pbd, a, mo, 2));
    TearParams<double> p;
    p.seed = 21;
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(-1, 1);
    int total = 0;
    for (int step = 0; step < 10; ++step) {
      for (std::size_t i = 0; i < a.size(); ++i) {
        a.x[i] = a.rest[i] + Vec3d(u(rng), u(rng), u(rng)) * 0.0012;
        a.v[i] = Vec3d(u(rng), u(rng), u(rng)) * 0.01;
      }
      PbdState<double> st;
      st.positions = a.x;
      st.velocities = a.v;
      st.radii.assign(a.size(), 0.0);
      st.rotations.assign(a.size(), pbd::Quat<double>{});
      pbd->setState(st);  // the device sheet's positions are the PBD backend's
      const std::uint32_t counter = a.step;
      const TearStepStats sc = cpu::tearStepCpu(a, p);
      TearFrameStats sg;
      const int made = tb->stepResident(p, counter, sg, step % 2 == 1);
      ASSERT_EQ(made, sc.splits) << "step " << step;
      EXPECT_EQ(sg.yielding, sc.yielding) << "step " << step;
      ASSERT_EQ(tb->residentSize(), a.size());
      total += made;
    }
    EXPECT_GT(total, 1000);
    TearSheet<double> b = a;
    tb->download(b, true);
    b.rebuildTopology();
    EXPECT_EQ(b.tris, a.tris) << "same seed, same topology";
    double err = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      err = std::max(err, norm(a.x[i] - b.x[i]) + norm(a.rest[i] - b.rest[i]) + std::abs(a.mass[i] - b.mass[i]));
      ASSERT_EQ(a.fixed[i], b.fixed[i]);
    }
    EXPECT_LT(err, 1e-12);
    EXPECT_TRUE(checkTearMesh(b).valid());
    const PbdModel<double> host = buildTearPbdModel(a, mo);
    cuda::PbdDevicePatch<double>* patch = cuda::pbdDevicePatch<double>(*pbd);
    ASSERT_NE(patch, nullptr);
    // Rest lengths from rest positions that agree to 1e-12 (checked above; measured ~1e-15 on a 0.5 m sheet,
    // a few ulps of the coordinates): the lengths agree to twice that.
    expectBlockEqual(patch->downloadBlock(0), host.blocks[0], 1e-13, "distance");
    expectBlockEqual(patch->downloadBlock(1), host.blocks[1], 1e-12, "bending");
  }
}

// The runner's model on CUDA (device-resident path, Jacobi): counters, surface and checkpoints stay right
// although the sheet lives on the device between frames.
TEST(TearingPatchGpu, SimulationModelOnCudaTearsAndRestoresCheckpoints) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  Scene s;
  s.file = "test-scene";
  s.models.tearing = true;
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.center = Vec3d(0.1, 0.05, 0);
  s.geometry.size = Vec3d(0.2, 0.1, 0.002);
  s.geometry.spacing = 0.01;
  s.material.youngs_modulus_pa = 1.5e3;
  s.material.density_kg_m3 = 1100;
  s.material.damping_per_s = 4;
  s.pbd.iterations = 8;
  s.pbd.stretch_compliance = 2e-4;
  s.pbd.solver = "jacobi";
  s.solver.gravity = Vec3d(0, 0, 0);
  s.fixed.push_back(FixedRegion{Vec3d(-1, -1, -1), Vec3d(0.001, 1, 1)});
  ToolSpec g;
  g.name = "grasper";
  g.kind = "grasper";
  g.radius = 0.004;
  g.length = 0.1;
  g.path = {ToolKeyframe{0.0, Vec3d(0.2, 0.0, 0), Vec3d(0, 1, 0)},
            ToolKeyframe{0.25, Vec3d(0.28, 0.0, 0), Vec3d(0, 1, 0)}};
  s.tools.push_back(g);
  auto m = makeTearingSimulation(compileScene(s), BackendKind::Cuda, Precision::Float32);
  EXPECT_EQ(m->backend(), BackendKind::Cuda);
  const std::size_t n0 = m->particleCount();
  double splits = 0;
  for (int f = 0; f < 15; ++f) {
    const FrameReport r = m->advance(1.0 / 60.0);
    ASSERT_TRUE(r.finite);
    splits += r.counters.at("splits");
    EXPECT_EQ(r.counters.at("particles"), double(m->particleCount()));
  }
  EXPECT_GT(splits, 0);
  EXPECT_EQ(m->particleCount(), n0 + std::size_t(splits));
  TriangleMesh surf;
  ASSERT_TRUE(m->currentSurface(surf));
  EXPECT_EQ(surf.vertices.size(), m->particleCount());
  m->saveCheckpoint();
  const std::size_t n1 = m->particleCount();
  std::vector<Vec3d> x1, x2;
  m->currentPositions(x1);
  m->advance(1.0 / 60.0);
  m->restoreCheckpoint();
  EXPECT_EQ(m->particleCount(), n1);
  m->currentPositions(x2);
  ASSERT_EQ(x1.size(), x2.size());
  for (std::size_t i = 0; i < x1.size(); ++i)
    ASSERT_EQ(norm(x1[i] - x2[i]), 0.0) << "restored positions, particle " << i;
  EXPECT_TRUE(m->advance(1.0 / 60.0).finite);
}

#endif  // INCISION_HAVE_CUDA
