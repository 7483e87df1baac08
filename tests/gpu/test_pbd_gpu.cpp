// CUDA PBD backend vs the CPU backend: same model, inputs and parameters for 100 frames; graph vs direct launches.
#include <gtest/gtest.h>

#if INCISION_HAVE_CUDA
#include <algorithm>
#include <cmath>
#include <functional>

#include "cpu_fallback/pbd_solver_cpu.h"
#include "host/scene/scene_compile.h"
#include "kernels/device_info.h"
#include "kernels/pbd_solver_cuda.h"
#include "tests/support/pbd_fixtures.h"

using namespace inc;

namespace {

bool haveDevice() { return cuda::queryDevices().device_count > 0; }

// A clamped lattice beam over a ground plane (met at varied contact insets, friction 0.5), pressed by a moving capsule
// tool (friction 0.8, sliding along its axis), its free end grasped by a compliant attachment that lifts it; volume
// preservation near the tool on.
template <typename T>
PbdModel<T> parityModel() {
  PbdModel<T> m = test::makeLatticeBeam<T>(0.06, 0.02, 0.02, 0.01, 2.0e4, true, 32);
  pbd::PlaneCollider<T> ground;
  ground.offset = T(-0.01);
  ground.friction = T(0.5);
  m.planes.push_back(ground);
  // Contact insets of 0, 1/4 and 1/2 radius in turn: every frame path meets the ground at r - inset.
  m.contact_inset.resize(m.size());
  for (std::size_t i = 0; i < m.size(); ++i) m.contact_inset[i] = m.rest_radii[i] * T(i % 3) / T(4);
  return m;
}

template <typename T>
PbdFrameInput<T> parityInput(const PbdModel<T>& m, int frame, bool attachments = true) {
  PbdFrameInput<T> in;
  const T t0 = T(frame) / T(100), t1 = T(frame + 1) / T(100);
  // Sliding along its own axis (y) as it presses down, with friction: it drags what it presses.
  pbd::CapsuleCollider<T> a, b;
  a.a = Vec3<T>(T(0.03), T(-0.01) + T(0.01) * t0, T(0.035) - T(0.01) * t0);
  a.b = Vec3<T>(T(0.03), T(0.03) + T(0.01) * t0, T(0.035) - T(0.01) * t0);
  a.radius = b.radius = T(0.004);
  a.friction = b.friction = T(0.8);
  b.a = Vec3<T>(T(0.03), T(-0.01) + T(0.01) * t1, T(0.035) - T(0.01) * t1);
  b.b = Vec3<T>(T(0.03), T(0.03) + T(0.01) * t1, T(0.035) - T(0.01) * t1);
  in.tools_from.push_back(a);
  in.tools_to.push_back(b);
  for (std::size_t i = 0; i < m.size() && attachments; ++i)
    if (m.rest_positions[i].x > T(0.055)) {
      in.attach_ids.push_back(std::int32_t(i));
      in.attach_from.push_back(m.rest_positions[i] + Vec3<T>(T(0), T(0), T(0.01) * t0));
      in.attach_to.push_back(m.rest_positions[i] + Vec3<T>(T(0), T(0), T(0.01) * t1));
      in.attach_compliance.push_back(T(1e-4));
    }
  return in;
}

// fused_max / cluster_max / grid_max: the frame paths' size limits (0 switches a path off); cluster_ctas forces the
// cluster frame's CTA count (0: as the model needs).
template <typename T>
void runParity(PbdSolverKind solver, double pos_tol_m, double radius_tol_m, int fused_max = 4096,
               int cluster_max = 8192, int cluster_ctas = 0, double chebyshev_rho = 0, bool attachments = true,
               int grid_max = 0) {
  const PbdModel<T> m = parityModel<T>();
  auto cpu = cpu::makePbdCpuBackend<T>();
  auto gpu = cuda::makePbdCudaBackend<T>();
  cpu->setModel(m);
  gpu->setModel(m);
  PbdStepParams<T> p;
  p.solver = solver;
  p.iterations = 8;
  p.substeps = 4;
  p.volume_influence = T(0.004);
  p.fused_max_particles = fused_max;
  p.cluster_max_particles = cluster_max;
  p.cluster_ctas = cluster_ctas;
  p.grid_max_particles = grid_max;
  p.use_graph = grid_max == 0;  // the grid frame runs only on frames launched directly
  p.chebyshev_rho = T(chebyshev_rho);
  PbdFrameStats sc, sg;
  for (int f = 0; f < 100; ++f) {
    const PbdFrameInput<T> in = parityInput(m, f, attachments);
    sc = cpu->advanceFrame(p, in);
    sg = gpu->advanceFrame(p, in);
  }
  ASSERT_TRUE(sc.finite);
  ASSERT_TRUE(sg.finite);
  if (grid_max > 0) {
    EXPECT_EQ(sg.path, "grid");
  }
  PbdState<T> a, b;
  cpu->getState(a);
  gpu->getState(b);
  double dx = 0, dr = 0, disp = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    dx = std::max(dx, double(norm(a.positions[i] - b.positions[i])));
    dr = std::max(dr, double(std::fabs(a.radii[i] - b.radii[i])));
    disp = std::max(disp, double(norm(a.positions[i] - m.rest_positions[i])));
  }
  std::printf(
      "solver %d, %zu-byte floats: max |x_cpu - x_gpu| %.3e m, max |r diff| %.3e m, max displacement %.3e m, "
      "volume-active %d/%d\n",
      int(solver), sizeof(T), dx, dr, disp, sc.volume_active, sg.volume_active);
  EXPECT_GT(disp, 1e-3);  // the scene does deform
  EXPECT_LT(dx, pos_tol_m);
  EXPECT_LT(dr, radius_tol_m);
  EXPECT_NEAR(sc.residual_max, sg.residual_max, 10 * pos_tol_m);
  EXPECT_EQ(sc.colors, sg.colors);
}

}  // namespace

// Tolerances: double, 1e-9 m (the backends differ only by FMA contraction and libm rounding); float, 20 um
// on a 6 cm beam (3e-4 of its length; float32 rounding through 100 frames x 4 substeps x 8 iterations, and
// a sample of the power-cell volume that lands on the other side of a cell face shifts a radius by a
// bisection step of r0 / 2^12 = 2 um).
TEST(PbdGpu, JacobiMatchesCpuAfter100FramesDouble) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  runParity<double>(PbdSolverKind::Jacobi, 1e-9, 1e-9);
}
TEST(PbdGpu, GaussSeidelMatchesCpuAfter100FramesDouble) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  runParity<double>(PbdSolverKind::GaussSeidel, 1e-9, 1e-9);
}
TEST(PbdGpu, JacobiMatchesCpuAfter100FramesFloat) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  runParity<float>(PbdSolverKind::Jacobi, 2e-5, 2e-5);
}
TEST(PbdGpu, GaussSeidelMatchesCpuAfter100FramesFloat) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  runParity<float>(PbdSolverKind::GaussSeidel, 2e-5, 2e-5);
}
// The same with the per-block/per-colour launches instead of the fused single-block frame kernel.
TEST(PbdGpu, UnfusedLaunchesMatchCpuAfter100Frames) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  runParity<double>(PbdSolverKind::Jacobi, 1e-9, 1e-9, 0, 0);
  runParity<double>(PbdSolverKind::GaussSeidel, 1e-9, 1e-9, 0, 0);
}
// The Jacobi frame in a thread-block cluster with more CTAs than the 63-sphere beam needs, so that constraint
// and particle ranges are split across CTAs (4 particles per CTA at 16) and nearly every gather and broadcast
// crosses to another CTA's shared memory; also an odd count. The single-block frame is off.
TEST(PbdGpu, ClusterFrameMatchesCpuAfter100Frames) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  for (int ctas : {16, 5, 1}) {
    runParity<double>(PbdSolverKind::Jacobi, 1e-9, 1e-9, 0, 8192, ctas);
    runParity<float>(PbdSolverKind::Jacobi, 2e-5, 2e-5, 0, 8192, ctas);
  }
}

// The Jacobi frame as one cooperative grid launch (kernels/pbd_grid_frame.cuh), plain and Chebyshev-accelerated,
// with attachments (separate attachment and contact phases) and without (contacts in the last gather). The same
// tolerances as the per-block launches.
TEST(PbdGpu, GridFrameMatchesCpuAfter100Frames) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  for (double rho : {0.0, 0.9})
    for (bool attachments : {true, false}) {
      runParity<double>(PbdSolverKind::Jacobi, 1e-9, 1e-9, 0, 0, 0, rho, attachments, 4096);
      runParity<float>(PbdSolverKind::Jacobi, 2e-5, 2e-5, 0, 0, 0, rho, attachments, 4096);
    }
}

// Chebyshev-accelerated Jacobi on per-block launches (the grid frame: GridFrameMatchesCpuAfter100Frames): the positions
// are blended in the contact kernel (with attachments) or in the last gather's (without), the multipliers in the same
// launch. The same tolerances as plain Jacobi.
TEST(PbdGpu, ChebyshevJacobiMatchesCpuAfter100Frames) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  for (bool attachments : {true, false}) {
    runParity<double>(PbdSolverKind::Jacobi, 1e-9, 1e-9, 4096, 8192, 0, 0.9, attachments);
    runParity<float>(PbdSolverKind::Jacobi, 2e-5, 2e-5, 4096, 8192, 0, 0.9, attachments);
  }
}

// The captured CUDA graph of per-phase launches, direct launches and the profiled path run the same kernels
// in the same order: bitwise-equal states. The fused single-block frame kernel runs the same physics calls
// in the same order but is compiled separately (the compiler may contract a multiply-add differently):
// equal within 1e-6 m on a 6 cm beam (float32). Both solvers.
TEST(PbdGpu, FusedGraphDirectAndProfiledFramesAreIdentical) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  const PbdModel<float> m = parityModel<float>();
  for (PbdSolverKind solver : {PbdSolverKind::Jacobi, PbdSolverKind::GaussSeidel}) {
    PbdState<float> s[4];
    for (int mode = 0; mode < 4; ++mode) {
      auto gpu = cuda::makePbdCudaBackend<float>();
      gpu->setModel(m);
      PbdStepParams<float> p;
      p.solver = solver;
      p.use_graph = mode != 1;
      p.profile_stages = mode == 2;
      p.fused_max_particles = mode == 0 ? 4096 : 0;  // mode 0: fused; 1: direct; 2: profiled; 3: graph
      p.cluster_max_particles = 0;                   // the cluster frame: ClusterFrameMatchesLaunches...
      p.grid_max_particles = 0;                      // the grid frame: GridFrameMatchesLaunches...
      for (int f = 0; f < 20; ++f) {
        const PbdFrameStats st = gpu->advanceFrame(p, parityInput(m, f));
        ASSERT_TRUE(st.finite);
        if (mode == 2) {
          // five stages, then one per solved block
          std::size_t solved = 0;
          for (const auto& b : m.blocks) solved += (b.solve && b.count() > 0) ? 1 : 0;
          ASSERT_EQ(st.stages.size(), 5u + solved);
          EXPECT_EQ(st.stages[1].stage, "constraints");
          double blocks_ms = 0;
          for (std::size_t k = 5; k < st.stages.size(); ++k) blocks_ms += st.stages[k].ms;
          EXPECT_LE(blocks_ms, st.stages[1].ms * (1 + 1e-9));
        }
      }
      gpu->getState(s[mode]);
    }
    for (int mode = 2; mode < 4; ++mode)
      for (std::size_t i = 0; i < m.size(); ++i) {
        EXPECT_EQ(s[1].positions[i].x, s[mode].positions[i].x) << "mode " << mode << " sphere " << i;
        EXPECT_EQ(s[1].positions[i].y, s[mode].positions[i].y) << "mode " << mode << " sphere " << i;
        EXPECT_EQ(s[1].positions[i].z, s[mode].positions[i].z) << "mode " << mode << " sphere " << i;
        EXPECT_EQ(s[1].radii[i], s[mode].radii[i]) << "mode " << mode << " sphere " << i;
      }
    for (std::size_t i = 0; i < m.size(); ++i) {
      EXPECT_LT(norm(s[0].positions[i] - s[1].positions[i]), 1e-6f) << "fused, sphere " << i;
      EXPECT_NEAR(s[0].radii[i], s[1].radii[i], 1e-6f) << "fused, sphere " << i;
    }
  }
}

// kinematic_from_positions on CUDA: the start positions gathered on the device give the frames of the downloaded
// positions passed as kinematic_from, bit for bit (graph frames, launches path).
TEST(PbdGpu, KinematicStartFromDevicePositionsEqualsExplicitStart) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  const PbdModel<float> m = parityModel<float>();
  auto a = cuda::makePbdCudaBackend<float>(), b = cuda::makePbdCudaBackend<float>();
  a->setModel(m);
  b->setModel(m);
  PbdStepParams<float> p;
  p.fused_max_particles = 0;
  p.cluster_max_particles = 0;
  p.grid_max_particles = 0;
  std::vector<std::int32_t> ids;
  for (std::size_t i = 0; i < m.size(); ++i)
    if (m.rest_positions[i].x > 0.055f) ids.push_back(std::int32_t(i));
  ASSERT_FALSE(ids.empty());
  PbdState<float> sa, sb;
  for (int f = 0; f < 10; ++f) {
    a->getState(sa);
    PbdFrameInput<float> ia, ib;
    ia.kinematic_ids = ib.kinematic_ids = ids;
    for (std::int32_t id : ids) {
      ia.kinematic_from.push_back(sa.positions[id]);
      ia.kinematic_to.push_back(m.rest_positions[id] + Vec3f(0, 0, 0.001f * f));
    }
    ib.kinematic_to = ia.kinematic_to;
    ib.kinematic_from_positions = true;
    ASSERT_TRUE(a->advanceFrame(p, ia).finite);
    ASSERT_TRUE(b->advanceFrame(p, ib).finite);
  }
  a->getState(sa);
  b->getState(sb);
  for (std::size_t i = 0; i < m.size(); ++i) {
    ASSERT_EQ(sa.positions[i].x, sb.positions[i].x) << i;
    ASSERT_EQ(sa.positions[i].y, sb.positions[i].y) << i;
    ASSERT_EQ(sa.positions[i].z, sb.positions[i].z) << i;
  }
}

// A liver-sized model (16 x 6 x 6 = 576 spheres at 4 mm, the bench_pbd case's size, on a ground plane) run for 30
// frames of a probe pressing and a grasp lifting (float32) on the per-block launches (mode 0) and twice on a
// whole-frame path (modes 1 and 2; `configure` sets the path for mode > 0). The path makes the same physics calls
// in the same gather order, compiled separately (multiply-add contraction may differ): within 1e-5 m of the
// launches; its replays are bitwise equal (deterministic: no atomics, fixed ownership). `path`: the frame path that
// modes 1 and 2 must report.
namespace {
void expectPathMatchesLaunchesOnLiverSizedModel(const char* what, const char* path,
                                                const std::function<void(PbdStepParams<float>&, int mode)>& configure) {
  PbdModel<float> m = test::makeLatticeBeam<float>(0.06, 0.02, 0.02, 0.004, 2.0e4, true, 32);
  ASSERT_EQ(m.size(), 576u);
  pbd::PlaneCollider<float> ground;
  ground.offset = -0.01f;
  m.planes.push_back(ground);
  PbdState<float> s[3];
  for (int mode = 0; mode < 3; ++mode) {
    auto gpu = cuda::makePbdCudaBackend<float>();
    gpu->setModel(m);
    PbdStepParams<float> p;
    p.solver = PbdSolverKind::Jacobi;
    p.iterations = 10;
    p.substeps = 4;
    p.volume_influence = 0.004f;
    p.fused_max_particles = 0;
    p.cluster_max_particles = 0;
    p.grid_max_particles = 0;
    configure(p, mode);
    for (int f = 0; f < 30; ++f) {
      const PbdFrameStats st = gpu->advanceFrame(p, parityInput(m, f));
      ASSERT_TRUE(st.finite);
      ASSERT_EQ(st.path, mode == 0 ? "launches" : path) << "frame " << f;
    }
    gpu->getState(s[mode]);
  }
  double dx = 0, disp = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    dx = std::max(dx, double(norm(s[0].positions[i] - s[1].positions[i])));
    disp = std::max(disp, double(norm(s[0].positions[i] - m.rest_positions[i])));
    EXPECT_EQ(s[1].positions[i].x, s[2].positions[i].x) << "sphere " << i;
    EXPECT_EQ(s[1].positions[i].y, s[2].positions[i].y) << "sphere " << i;
    EXPECT_EQ(s[1].positions[i].z, s[2].positions[i].z) << "sphere " << i;
    EXPECT_NEAR(s[0].rotations[i].w, s[1].rotations[i].w, 1e-4f) << "sphere " << i;
    EXPECT_NEAR(s[0].rotations[i].x, s[1].rotations[i].x, 1e-4f) << "sphere " << i;
  }
  std::printf("576 spheres, %s vs launches after 30 frames: max |dx| %.3e m (max displacement %.3e m)\n", what, dx,
              disp);
  EXPECT_GT(disp, 1e-3);
  EXPECT_LT(dx, 1e-5);
}
}  // namespace

// The cluster frame with as many CTAs as the model needs (9).
TEST(PbdGpu, ClusterFrameMatchesLaunchesOnLiverSizedModel) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  expectPathMatchesLaunchesOnLiverSizedModel("cluster frame", "cluster", [](PbdStepParams<float>& p, int mode) {
    if (mode > 0) p.cluster_max_particles = 8192;
  });
}

// The grid frame (every frame launched directly, its case), plain and Chebyshev-accelerated Jacobi; the Chebyshev
// weights are the host's on both paths.
TEST(PbdGpu, GridFrameMatchesLaunchesOnLiverSizedModel) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  for (float rho : {0.0f, 0.9f})
    expectPathMatchesLaunchesOnLiverSizedModel(rho > 0 ? "grid frame, Chebyshev 0.9" : "grid frame", "grid",
                                               [rho](PbdStepParams<float>& p, int mode) {
                                                 p.chebyshev_rho = rho;
                                                 p.use_graph = false;
                                                 if (mode > 0) p.grid_max_particles = 8192;
                                               });
}

#else
TEST(PbdGpu, SkippedWithoutCuda) { GTEST_SKIP() << "built without CUDA"; }
#endif

#if INCISION_HAVE_CUDA
#include "host/scene/scene_loader.h"
#include "host/sim/metaball_simulation.h"
#include "tests/support/repo_paths.h"

// The shipped grasp scene on the CUDA backend: 100 frames, finite, grasped, and within 1 mm of the CPU run
// (float32; the tool path and grasp selection are identical host code).
TEST(PbdGpu, LiverGraspSceneMatchesCpuAfter100Frames) {
  if (!haveDevice()) {
    GTEST_SKIP() << "no CUDA device";
  }
  const Scene s = loadSceneFile(test::sourcePath("scenes/liver_grasp.json"));
  auto cpu = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  auto gpu = makeMetaballSimulation(compileScene(s), BackendKind::Cuda, Precision::Float32);
  ASSERT_EQ(gpu->backend(), BackendKind::Cuda);
  FrameReport rc, rg;
  for (int f = 0; f < 100; ++f) {
    rc = cpu->advance(s.solver.frame_dt);
    rg = gpu->advance(s.solver.frame_dt);
    ASSERT_TRUE(rg.finite);
  }
  EXPECT_EQ(rc.counters.at("grasped"), rg.counters.at("grasped"));
  std::vector<Vec3d> a, b;
  cpu->currentPositions(a);
  gpu->currentPositions(b);
  double dx = 0;
  for (std::size_t i = 0; i < a.size(); ++i) dx = std::max(dx, norm(a[i] - b[i]));
  std::printf("liver_grasp CPU vs CUDA after 100 frames: max |dx| %.3e m, max displacement %.3e m\n", dx,
              rc.max_displacement);
  EXPECT_LT(dx, 1e-3);
}
#endif

#if INCISION_HAVE_CUDA
// The shipped drop scene (colliders, contact insets) with each PBD path the CUDA backend has (Jacobi: fused single
// block, cluster, grid frame, per-block launches, as the thresholds pick them; Gauss-Seidel): 60 frames in float64
// within 1e-6 m of the CPU (the same solver on both), the skin on the pad (a plane and a box).
TEST(PbdGpu, LiverDropSceneCollidersMatchCpu) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  for (const char* solver : {"jacobi", "gauss_seidel"}) {
    Scene s = loadSceneFile(test::sourcePath("scenes/liver_drop.json"));
    s.pbd.solver = solver;
    auto cpu = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
    auto gpu = makeMetaballSimulation(compileScene(s), BackendKind::Cuda, Precision::Float64);
    for (int f = 0; f < 60; ++f) {
      ASSERT_TRUE(cpu->advance(s.solver.frame_dt).finite);
      ASSERT_TRUE(gpu->advance(s.solver.frame_dt).finite);
    }
    std::vector<Vec3d> a, b;
    cpu->currentPositions(a);
    gpu->currentPositions(b);
    double dx = 0;
    for (std::size_t i = 0; i < a.size(); ++i) dx = std::max(dx, norm(a[i] - b[i]));
    TriangleMesh mesh;
    ASSERT_TRUE(gpu->currentSurface(mesh));
    double low = 1e30;
    for (const Vec3d& v : mesh.vertices) low = std::min(low, v.z);
    std::printf("liver_drop (%s) CPU vs CUDA after 60 frames: max |dx| %.3e m, lowest skin vertex %.4f m\n", solver, dx,
                low);
    EXPECT_LT(dx, 1e-6) << solver;
    EXPECT_GT(low, -0.055) << solver << ": above the table";
  }
}
#endif
