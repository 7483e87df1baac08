// MlsSimulation from a Scene: frame reports, fixed regions, checkpoints, step scaling, bad input.
#include <gtest/gtest.h>

#include <cmath>

#include "host/scene/scene_compile.h"
#include "host/sim/mls_simulation.h"
#include "model/input_error.h"
#if INCISION_HAVE_CUDA
#include "kernels/device_info.h"
#endif

using namespace inc;

namespace {

// The scenes/beam.json cantilever at a coarser spacing (5 mm: 16 x 4 x 4 particles) so that it runs fast.
Scene beamScene() {
  Scene s;
  s.file = "<test beam>";
  s.name = "beam";
  s.geometry.kind = GeometrySpec::Kind::Beam;
  s.geometry.center = Vec3d(0.04, 0, 0);
  s.geometry.size = Vec3d(0.08, 0.02, 0.02);
  s.geometry.spacing = 0.005;
  s.material.youngs_modulus_pa = 2e5;
  s.material.poisson_ratio = 0.4;
  s.material.density_kg_m3 = 1060;
  s.material.damping_per_s = 10;
  s.models.mls = true;
  s.solver.frame_dt = 1.0 / 60.0;
  FixedRegion clamp;
  clamp.min = Vec3d(-0.001, -0.011, -0.011);
  clamp.max = Vec3d(0.0051, 0.011, 0.011);
  s.fixed.push_back(clamp);
  return s;
}

}  // namespace

TEST(MlsSimulation, BeamFramesReportEnergiesAndHoldTheClamp) {
  for (const Precision prec : {Precision::Float32, Precision::Float64}) {
    const Scene scene = beamScene();
    auto sim = makeMlsSimulation(compileScene(scene), BackendKind::Cpu, prec);
    EXPECT_EQ(sim->name(), "mls");
    EXPECT_EQ(sim->backend(), BackendKind::Cpu);
    ASSERT_EQ(sim->particleCount(), 16u * 4u * 4u);
    std::vector<Vec3d> x0, x;
    sim->currentPositions(x0);
    FrameReport r;
    for (int f = 0; f < 6; ++f) r = sim->advance(scene.solver.frame_dt);
    EXPECT_TRUE(r.finite);
    EXPECT_GT(r.substeps, 0);
    EXPECT_NEAR(r.dt * r.substeps, scene.solver.frame_dt, 1e-12);
    EXPECT_LE(r.dt, scene.solver.safety * r.counters.at("stable_dt_s") * (1 + 1e-9));
    ASSERT_EQ(r.stages.size(), 4u);
    EXPECT_EQ(r.stages[1].stage, "stress");
    // The beam sags: gravity did work, strain energy stored, nothing exceeds the work done.
    EXPECT_LT(r.potential_energy, 0.0);
    EXPECT_GT(r.elastic_energy, 0.0);
    EXPECT_LE(r.kinetic_energy + r.elastic_energy, -r.potential_energy * 1.01);
    EXPECT_GT(r.max_displacement, 1e-4);
    EXPECT_LT(r.max_displacement, 0.02);
    EXPECT_EQ(r.counters.at("isolated_particles"), 0.0);
    sim->currentPositions(x);
    for (std::size_t i = 0; i < x.size(); ++i)
      if (x0[i].x < 0.0051) {
        EXPECT_EQ(norm(x[i] - x0[i]), 0.0) << "clamped particle " << i << " moved";
      }
    // The tip went down.
    double tip = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (x0[i].x > 0.075) tip = std::min(tip, x[i].z - x0[i].z);
    EXPECT_LT(tip, -1e-4);
  }
}

TEST(MlsSimulation, CheckpointRestoresStateAndScalingDoublesSubsteps) {
  const Scene scene = beamScene();
  auto sim = makeMlsSimulation(compileScene(scene), BackendKind::Cpu, Precision::Float64);
  sim->advance(scene.solver.frame_dt);
  sim->saveCheckpoint();
  std::vector<Vec3d> saved, again;
  sim->currentPositions(saved);
  const FrameReport a = sim->advance(scene.solver.frame_dt);
  sim->restoreCheckpoint();
  sim->currentPositions(again);
  for (std::size_t i = 0; i < saved.size(); ++i) EXPECT_EQ(norm(saved[i] - again[i]), 0.0);
  // Deterministic: the same frame again gives the same energies exactly.
  const FrameReport b = sim->advance(scene.solver.frame_dt);
  EXPECT_EQ(a.kinetic_energy, b.kinetic_energy);
  EXPECT_EQ(a.elastic_energy, b.elastic_energy);
  sim->scaleTimeStep(0.5);
  const FrameReport c = sim->advance(scene.solver.frame_dt);
  EXPECT_GE(c.substeps, int(1.8 * a.substeps));  // 2x, less what the stiffening of the sag may vary
  EXPECT_TRUE(c.finite);
}

TEST(MlsSimulation, BadSceneInputIsRefusedWithItsKey) {
  Scene scene = beamScene();
  auto keyOf = [](const Scene& s, BackendKind b) {
    try {
      makeMlsSimulation(compileScene(s), b, Precision::Float32);
    } catch (const InputError& e) {
      return e.key();
    }
    return std::string("<no error>");
  };
  EXPECT_EQ(keyOf(scene, BackendKind::Auto), "solver.backend");
  Scene few = scene;
  few.solver.substeps = 1;  // 1/60 s in one step is far above the stable limit
  EXPECT_EQ(keyOf(few, BackendKind::Cpu), "solver.substeps");
  Scene nu = scene;
  nu.material.poisson_ratio = 0.5;
  EXPECT_EQ(keyOf(nu, BackendKind::Cpu), "material.poisson_ratio");
  Scene spacing = scene;
  spacing.geometry.spacing = -1;
  EXPECT_EQ(keyOf(spacing, BackendKind::Cpu), "geometry.spacing_m");
  Scene support = scene;
  support.mls.support_factor = 10;
  EXPECT_EQ(keyOf(support, BackendKind::Cpu), "mls.support_factor");
  Scene box = scene;
  box.fixed[0].min.x = 1.0;  // min > max
  EXPECT_EQ(keyOf(box, BackendKind::Cpu), "fixed[0]");
  // CUDA asked for where no device is usable: refused with a reason, never a crash.
#if INCISION_HAVE_CUDA
  const bool gpu = inc::cuda::queryDevices().device_count > 0;
#else
  const bool gpu = false;
#endif
  if (!gpu) {
    EXPECT_NE(keyOf(scene, BackendKind::Cuda), "<no error>");
  }
}

TEST(MlsSimulation, GrasperCarriesItsParticlesAlongThePath) {
  // A grasper of radius 6 mm at the free tip lifts it 5 mm over 0.1 s and holds: the grasped particles sit
  // exactly on the tool's displacement at each frame end; the beam between clamp and tool bends upwards.
  Scene scene = beamScene();
  scene.solver.gravity = Vec3d(0, 0, 0);
  ToolSpec tool;
  tool.name = "forceps";
  tool.kind = "grasper";
  tool.radius = 0.006;
  ToolKeyframe k0, k1;
  k0.t = 0.0;
  k0.position = Vec3d(0.0775, 0, 0);
  k1.t = 0.1;
  k1.position = Vec3d(0.0775, 0, 0.005);
  tool.path = {k0, k1};
  scene.tools.push_back(tool);
  auto sim = makeMlsSimulation(compileScene(scene), BackendKind::Cpu, Precision::Float64);
  std::vector<Vec3d> x0, x;
  sim->currentPositions(x0);
  FrameReport r;
  for (int f = 1; f <= 9; ++f) {
    r = sim->advance(scene.solver.frame_dt);
    ASSERT_TRUE(r.finite);
    const double lift = 0.005 * std::min(1.0, f * scene.solver.frame_dt / 0.1);
    sim->currentPositions(x);
    for (std::size_t i = 0; i < x.size(); ++i)
      if (norm(x0[i] - k0.position) <= tool.radius) {
        EXPECT_NEAR(x[i].z - x0[i].z, lift, 1e-12) << "frame " << f;
      }
  }
  EXPECT_GT(r.counters.at("grasped_particles"), 0.0);
  EXPECT_GT(r.elastic_energy, 0.0);
  // Mid-span rises, less than the tool.
  double mid = 0;
  int count = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (std::abs(x0[i].x - 0.0425) < 0.003) {
      mid += x[i].z - x0[i].z;
      ++count;
    }
  ASSERT_GT(count, 0);
  EXPECT_GT(mid / count, 0.0005);
  EXPECT_LT(mid / count, 0.005);
  // A grasper that touches nothing is refused with its key.
  scene.tools[0].path[0].position = Vec3d(1, 1, 1);
  try {
    makeMlsSimulation(compileScene(scene), BackendKind::Cpu, Precision::Float64);
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "tools[0]");
  }
}
