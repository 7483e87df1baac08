// Cut tests on the GPU: sphere and crossing-pair masks equal the CPU decisions; the MLS coupling groups and a
// whole scripted dissection (nodal points coupled while the blade is in) agree with the CPU.
#if INCISION_HAVE_CUDA
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "cpu_fallback/neighbor_bruteforce.h"
#include "host/backends/solver_factory.h"
#include "host/cut/cut_nodal_points.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "host/sim/dissection_simulation.h"
#include "kernels/cut_cuda.h"
#include "kernels/device_info.h"
#include "model/mls_solver.h"
#include "tests/support/cut_block_scene.h"
#include "tests/support/cut_fixtures.h"
#include "tests/support/mls_test_scenes.h"

using namespace inc;

namespace {

bool noDevice() { return inc::cuda::queryDevices().device_count == 0; }

SweptSurface curvedCut() {
  std::vector<BladePose> poses;
  for (int k = 0; k <= 10; ++k) {
    const double x = -0.08 + 0.016 * k, z = 0.006 * std::sin(0.6 * k);
    poses.push_back({Vec3d(x, -0.1, z - 0.01), Vec3d(x, 0.1, z + 0.012)});
  }
  return sweepSurface(poses);
}

TEST(CutGpu, SphereMaskEqualsCpu) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  const MetaballModel m = cuttest::latticeBlock(16, 10, 8);
  const SweptSurface s = curvedCut();
  const auto cpu = findCutSpheres(s, m.rest_centers, m.rest_radii);
  const auto mask = cuda::cutSphereMaskCuda(s.vertices, s.triangles, m.rest_centers, m.rest_radii);
  ASSERT_EQ(mask.size(), m.size());
  std::vector<std::int32_t> gpu;
  for (std::size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) gpu.push_back(std::int32_t(i));
  EXPECT_GT(cpu.size(), 0u);
  EXPECT_EQ(gpu, cpu);
}

TEST(CutGpu, CrossingPairMaskEqualsCpu) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  const MetaballModel m = cuttest::latticeBlock(16, 10, 8);
  const SweptSurface s = curvedCut();
  const SphereCutResult r = cutSpheres(m, s);
  const NeighborLists all = cpu::bruteForceNeighbors(r.points.positions, r.points.positions,
                                                     std::vector<double>{2.5 * r.points.spacing}, true);
  const auto mask = cuda::crossingPairMaskCuda(s.vertices, s.triangles, r.points.positions, all.offsets, all.indices);
  ASSERT_EQ(mask.size(), all.indices.size());
  std::size_t crossing = 0;
  for (std::size_t q = 0; q < all.queryCount(); ++q)
    for (auto k = all.offsets[q]; k < all.offsets[q + 1]; ++k) {
      const bool c = segmentCrossesSweptSurface(s, r.points.positions[q], r.points.positions[all.indices[k]]);
      ASSERT_EQ(bool(mask[k]), c) << "query " << q << " entry " << k;
      crossing += c;
    }
  EXPECT_GT(crossing, 0u);
}

// Coupling groups on a 9 x 6 x 6 lattice: one per 3 x 3 x 3 corner block, each on two springs to fixed anchors.
struct CornerGroups {
  MlsCouplingGroups groups;
  std::vector<Vec3d> anchors;
};
CornerGroups cornerGroups(const std::vector<Vec3d>& rest) {
  CornerGroups out;
  MlsCouplingGroups& g = out.groups;
  Vec3d lo = rest[0];
  for (const auto& x : rest)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], x[k]);
  for (int block = 0; block < 3; ++block) {
    Vec3d c;
    int n = 0;
    for (std::size_t i = 0; i < rest.size(); ++i)
      if (int((rest[i].x - lo.x) / 0.015 + 1e-9) == block && rest[i].y < lo.y + 0.014 && rest[i].z < lo.z + 0.014) {
        g.members.push_back(std::int32_t(i));
        c += rest[i];
        ++n;
      }
    g.member_offsets.push_back(std::int32_t(g.members.size()));
    g.rest_centres.push_back(c * (1.0 / n));
    for (int k = 0; k < 2; ++k) {
      g.rest_lengths.push_back(0.01);
      g.stiffnesses.push_back(20.0 + 10.0 * k);
      out.anchors.push_back(g.rest_centres.back() + Vec3d(0.0, k ? 0.012 : 0.0, k ? 0.0 : -0.011));
    }
    g.spring_offsets.push_back(std::int32_t(g.rest_lengths.size()));
  }
  return out;
}

std::vector<Vec3d> hashedDisplacement(std::size_t n) {
  std::vector<Vec3d> u0(n);
  for (std::size_t i = 0; i < n; ++i)
    u0[i] = Vec3d(mls_test::hashSigned(i), mls_test::hashSigned(i + 7), mls_test::hashSigned(i + 13)) * 2e-4;
  return u0;
}

// The same coupling groups on both backends, float64, from a non-uniform initial displacement: after 200 steps
// every displacement and every group's eq. 13 displacement agree to 1e-9 relative.
TEST(CutGpu, MlsCouplingGroupsMatchCpu) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  MlsBuildInput in = mls_test::blockInput(9, 6, 6, 0.005);
  in.material.damping_per_s = 1.0;
  auto cpu = makeMlsSolver(in, BackendKind::Cpu, Precision::Float64);
  auto gpu = makeMlsSolver(in, BackendKind::Cuda, Precision::Float64);
  const CornerGroups cg = cornerGroups(cpu->restPositions());
  const std::vector<Vec3d> u0 = hashedDisplacement(cpu->size());
  for (MlsSolver* s : {cpu.get(), gpu.get()}) {
    s->setCouplingGroups(cg.groups);
    s->setCouplingAnchors(cg.anchors);
    s->setDisplacements(u0);
  }
  const double dt = 0.5 * cpu->stableTimeStep();
  EXPECT_EQ(cpu->stableTimeStep(), gpu->stableTimeStep());
  cpu->step(dt, 200);
  gpu->step(dt, 200);
  std::vector<Vec3d> a, b, ga, gb;
  cpu->displacements(a);
  gpu->displacements(b);
  cpu->couplingDisplacements(ga);
  gpu->couplingDisplacements(gb);
  const double scale = mls_test::maxNorm(a);
  ASSERT_GT(scale, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_LT(norm(a[i] - b[i]), 1e-9 * scale) << i;
  for (std::size_t k = 0; k < ga.size(); ++k) EXPECT_LT(norm(ga[k] - gb[k]), 1e-9 * scale) << k;
}

// The graph path (setStageTiming(false): each exchange's substeps replayed as one CUDA graph, force pass and next
// drift fused) makes the same per-particle calls in the same order as the timed launches: the same bits, float32
// and float64, over frames whose anchors move (the graph replays with new anchor values) and whose substep count
// changes (a new capture); so does the persistent path (the substeps in one cooperative launch, grid barriers
// between the phases); the CPU agrees to 1e-9 relative in float64.
TEST(CutGpu, MlsGraphFramesEqualTimedLaunchesBitForBit) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  MlsBuildInput in = mls_test::blockInput(9, 6, 6, 0.005);
  in.material.damping_per_s = 1.0;
  for (Precision prec : {Precision::Float32, Precision::Float64}) {
    auto timed = makeMlsSolver(in, BackendKind::Cuda, prec);
    auto graph = makeMlsSolver(in, BackendKind::Cuda, prec);
    auto persistent = makeMlsSolver(in, BackendKind::Cuda, prec);
    auto cpu = makeMlsSolver(in, BackendKind::Cpu, prec);
    graph->setStageTiming(false);
    graph->setPersistentSubsteps(false);  // the CUDA graph
    persistent->setStageTiming(false);    // one cooperative launch per frame (the default when untimed)
    const CornerGroups cg = cornerGroups(timed->restPositions());
    const std::vector<Vec3d> u0 = hashedDisplacement(timed->size());
    for (MlsSolver* s : {timed.get(), graph.get(), persistent.get(), cpu.get()}) {
      s->setCouplingGroups(cg.groups);
      s->setDisplacements(u0);
    }
    const double frame = 40.0 * timed->stableTimeStep();
    double substeps_ms = 0.0;
    for (int f = 0; f < 6; ++f) {
      std::vector<Vec3d> anchors = cg.anchors;
      for (Vec3d& a : anchors) a += Vec3d(0.0005 * f, -0.0003 * f, 0.0002 * f);
      const int fixed = f < 3 ? 60 : 75;
      MlsFrameStats st[4];
      int k = 0;
      for (MlsSolver* s : {timed.get(), graph.get(), persistent.get(), cpu.get()}) {
        s->setCouplingAnchors(anchors);
        st[k++] = s->advance(frame, fixed);
      }
      EXPECT_EQ(st[0].substeps, st[1].substeps);
      EXPECT_EQ(st[0].substeps, st[2].substeps);
      EXPECT_EQ(st[2].ms_stress, 0.0);
      EXPECT_TRUE(st[1].totals.finite);
      EXPECT_EQ(st[1].ms_stress, 0.0);  // no per-stage events on the graph path
      substeps_ms += st[1].ms_substeps;
    }
    EXPECT_GT(substeps_ms, 0.0);
    std::vector<Vec3d> a, b, c, p, va, vb, vp;
    timed->displacements(a);
    graph->displacements(b);
    persistent->displacements(p);
    cpu->displacements(c);
    timed->velocities(va);
    graph->velocities(vb);
    persistent->velocities(vp);
    const double scale = mls_test::maxNorm(a);
    ASSERT_GT(scale, 1e-5);
    const auto same = [](const Vec3d& x, const Vec3d& y) { return x.x == y.x && x.y == y.y && x.z == y.z; };
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_TRUE(same(a[i], b[i]) && same(va[i], vb[i])) << "graph, particle " << i;
      ASSERT_TRUE(same(a[i], p[i]) && same(va[i], vp[i])) << "persistent, particle " << i;
      if (prec == Precision::Float64) {
        ASSERT_LT(norm(a[i] - c[i]), 1e-9 * scale) << i;
      }
    }
  }
}

// rebuildMlsSolver reuses the CUDA solver (the same object, its buffers, stream and graph) for another model, and
// the replaced solver then runs exactly as a new one built on that model: the same bits after coupled frames on
// the graph path, in both precisions; a replacement by a smaller model too.
TEST(CutGpu, ReplacedMlsSolverRunsAsANewOne) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  for (Precision prec : {Precision::Float32, Precision::Float64}) {
    MlsBuildInput first = mls_test::blockInput(9, 6, 6, 0.005);
    first.material.damping_per_s = 1.0;
    std::unique_ptr<MlsSolver> reused = makeMlsSolver(first, BackendKind::Cuda, prec);
    reused->setStageTiming(false);
    const CornerGroups g0 = cornerGroups(reused->restPositions());
    reused->setCouplingGroups(g0.groups);
    reused->setCouplingAnchors(g0.anchors);
    reused->setDisplacements(hashedDisplacement(reused->size()));
    reused->advance(30.0 * reused->stableTimeStep(), 45);
    for (int shape = 0; shape < 2; ++shape) {
      MlsBuildInput next = shape == 0 ? mls_test::blockInput(12, 6, 6, 0.005) : mls_test::blockInput(9, 6, 5, 0.005);
      next.material.damping_per_s = 2.0;
      const MlsSolver* before = reused.get();
      rebuildMlsSolver(reused, next, BackendKind::Cuda, prec);
      EXPECT_EQ(reused.get(), before) << "the CUDA solver was not reused";
      std::unique_ptr<MlsSolver> fresh = makeMlsSolver(next, BackendKind::Cuda, prec);
      fresh->setStageTiming(false);
      ASSERT_EQ(reused->size(), fresh->size());
      EXPECT_EQ(reused->stableTimeStep(), fresh->stableTimeStep());  // the coupling of the old model is gone
      const CornerGroups cg = cornerGroups(fresh->restPositions());
      const std::vector<Vec3d> u0 = hashedDisplacement(fresh->size());
      for (MlsSolver* s : {reused.get(), fresh.get()}) {
        s->setCouplingGroups(cg.groups);
        s->setCouplingAnchors(cg.anchors);
        s->setDisplacements(u0);
      }
      for (int f = 0; f < 3; ++f) {
        const MlsFrameStats a = reused->advance(30.0 * fresh->stableTimeStep(), 45);
        const MlsFrameStats b = fresh->advance(30.0 * fresh->stableTimeStep(), 45);
        EXPECT_EQ(a.substeps, b.substeps);
        EXPECT_EQ(a.totals.elastic_energy, b.totals.elastic_energy);
      }
      std::vector<Vec3d> x, y;
      reused->displacements(x);
      fresh->displacements(y);
      ASSERT_GT(mls_test::maxNorm(y), 0.0);
      for (std::size_t i = 0; i < x.size(); ++i) {
        ASSERT_EQ(x[i].x, y[i].x) << i;
        ASSERT_EQ(x[i].y, y[i].y) << i;
        ASSERT_EQ(x[i].z, y[i].z) << i;
      }
    }
  }
}

// The same scripted cut on both backends, float64: the same topology every frame and positions within 1e-6 m (the
// spheres and the nodal points). With Gauss-Seidel and with Jacobi (whose stroke rebuilds are colouring-free models
// uploaded into reused buffers); with the blade as a contact (points and spheres pushed out of its capsule, the
// points sliding on it with friction) and the
// stroke's end applied frames after the blade leaves; with each conversion prepared beside a frame and applied at
// the next.
void expectSameDissectionOnBothBackends(const std::string& solver, double blade_radius = 0.0, int stroke_end_frames = 0,
                                        int conversion_delay_frames = 0, double blade_friction = 0.0) {
  Scene s = cuttest::dissectionBlock("<gpu test:dissection parity>", true);
  s.pbd.solver = solver;
  s.cutting.samples_per_diameter = 3;
  s.cutting.exchanges_per_frame = 2;
  s.cutting.blade_radius_m = blade_radius;
  s.cutting.stroke_end_frames = stroke_end_frames;
  s.cutting.conversion_delay_frames = conversion_delay_frames;
  s.cutting.blade_friction = blade_friction;
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(1, 1, -0.008)}};  // the bottom layer of centres (z = -0.01)
  s.tools = {cuttest::scalpel({{0.05, Vec3d(-0.05, 0.002, 0.0), Vec3d(0, 0, 1)},
                               {0.2, Vec3d(0.05, 0.002, 0.0), Vec3d(0, 0, 1)},
                               {0.3, Vec3d(0.05, 0.002, 0.0), Vec3d(0, 0, 1)}})};
  auto cpu = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  auto gpu = makeDissectionSimulation(compileScene(s), BackendKind::Cuda, Precision::Float64);
  ASSERT_EQ(gpu->backend(), BackendKind::Cuda);
  double points_max = 0;
  for (int f = 0; f < 24; ++f) {
    const FrameReport a = cpu->advance(1.0 / 60.0), b = gpu->advance(1.0 / 60.0);
    ASSERT_TRUE(a.finite && b.finite) << f;
    for (const char* key :
         {"spheres", "nodal_points", "interface_spheres", "coupling_springs", "sphere_components", "cuts_applied",
          "spheres_added_last_cut", "repack_boundary_points", "repack_medial_points", "supports_cut"})
      ASSERT_EQ(a.counters.at(key), b.counters.at(key)) << key << " frame " << f;
    points_max = std::max(points_max, a.counters.at("nodal_points"));
    std::vector<Vec3d> xa, xb;
    cpu->currentPositions(xa);
    gpu->currentPositions(xb);
    ASSERT_EQ(xa.size(), xb.size());
    for (std::size_t i = 0; i < xa.size(); ++i)
      ASSERT_LT(norm(xa[i] - xb[i]), 1e-6) << "frame " << f << " sphere " << i;
    RenderLayers la, lb;
    cpu->renderLayers(la);
    gpu->renderLayers(lb);
    ASSERT_EQ(la.nodal_points.size(), lb.nodal_points.size()) << f;
    for (std::size_t i = 0; i < la.nodal_points.size(); ++i)
      ASSERT_LT(norm(la.nodal_points[i] - lb.nodal_points[i]), 1e-6) << "frame " << f << " point " << i;
  }
  EXPECT_GT(points_max, 0.0);
}

TEST(CutGpu, ScriptedDissectionHasTheSameTopologyOnBothBackends) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  expectSameDissectionOnBothBackends("gauss_seidel");
}

TEST(CutGpu, JacobiDissectionHasTheSameTopologyOnBothBackends) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  expectSameDissectionOnBothBackends("jacobi");
}

TEST(CutGpu, BladeContactAndDeferredEndMatchCpu) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  expectSameDissectionOnBothBackends("jacobi", 0.002, 3, 0, 0.5);  // with the blade's friction on the points
}

TEST(CutGpu, DelayedConversionsMatchCpu) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  expectSameDissectionOnBothBackends("jacobi", 0.0, 3, 1);
}

}  // namespace
#endif
