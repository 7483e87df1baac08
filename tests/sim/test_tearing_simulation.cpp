// The tearing sheet as a SimulationModel: scene -> sheet, grasper pull tears it, scalpel removes tissue, bad scenes
// refused.
#include <gtest/gtest.h>

#include <cstdio>

#include "host/scene/scene_compile.h"
#include "host/sim/tearing_simulation.h"
#include "model/input_error.h"

using namespace inc;

namespace {
Scene sheetScene() {
  Scene s;
  s.file = "test-scene";
  s.models.tearing = true;
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.center = Vec3d(0.1, 0.05, 0);
  s.geometry.size = Vec3d(0.2, 0.1, 0.002);
  s.geometry.spacing = 0.01;
  s.material.youngs_modulus_pa = 1.5e3;  // k; tau_f = 150 Pa
  s.material.density_kg_m3 = 1100;
  s.material.damping_per_s = 4;
  s.pbd.iterations = 8;
  s.pbd.stretch_compliance = 2e-4;
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
  return s;
}
}  // namespace

TEST(TearingSimulation, GrasperPullTearsSheetAndReportsCounters) {
  const Scene scene = sheetScene();
  auto m = makeTearingSimulation(compileScene(scene), BackendKind::Cpu, Precision::Float64);
  EXPECT_EQ(m->name(), "tearing_sheet");
  const std::size_t n0 = m->particleCount();
  EXPECT_EQ(n0, 21u * 11u);
  double splits = 0;
  for (int f = 0; f < 15; ++f) {
    const FrameReport r = m->advance(1.0 / 60.0);
    ASSERT_TRUE(r.finite);
    splits += r.counters.at("splits");
  }
  EXPECT_GT(splits, 0);
  EXPECT_EQ(m->particleCount(), n0 + std::size_t(splits));
  TriangleMesh surf;
  ASSERT_TRUE(m->currentSurface(surf));
  EXPECT_EQ(surf.vertices.size(), m->particleCount());
  // Checkpoint round trip.
  m->saveCheckpoint();
  const std::size_t n1 = m->particleCount();
  m->advance(1.0 / 60.0);
  m->restoreCheckpoint();
  EXPECT_EQ(m->particleCount(), n1);
}

TEST(TearingSimulation, ScalpelRemovesTissueAndTubeBuilds) {
  Scene scene = sheetScene();
  scene.tools.clear();
  ToolSpec sc;
  sc.kind = "scalpel";
  sc.radius = 0.006;
  sc.length = 0.0;
  sc.path = {ToolKeyframe{0.0, Vec3d(0.1, 0.0, 0), Vec3d(0, 1, 0)},
             ToolKeyframe{0.1, Vec3d(0.1, 0.1, 0), Vec3d(0, 1, 0)}};
  scene.tools.push_back(sc);
  auto m = makeTearingSimulation(compileScene(scene), BackendKind::Cpu, Precision::Float32);
  double removed = 0;
  for (int f = 0; f < 8; ++f) removed += m->advance(1.0 / 60.0).counters.at("removed");
  EXPECT_GT(removed, 0.0);
  TriangleMesh surf;
  m->currentSurface(surf);
  EXPECT_LT(surf.triangles.size(), 2u * 20u * 10u);  // tissue along the blade's path is gone
  Scene leg = sheetScene();
  leg.geometry.kind = GeometrySpec::Kind::Beam;
  leg.geometry.size = Vec3d(0.2, 0.06, 0.06);
  leg.tools.clear();
  auto t = makeTearingSimulation(compileScene(leg), BackendKind::Cpu, Precision::Float32);
  EXPECT_GT(t->particleCount(), 100u);
  EXPECT_TRUE(t->advance(1.0 / 60.0).finite);
}

TEST(TearingSimulation, BadScenesRefused) {
  Scene s = sheetScene();
  s.models.tearing = false;
  EXPECT_THROW(makeTearingSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32), InputError);
  s = sheetScene();
  s.geometry.kind = GeometrySpec::Kind::Sphere;
  EXPECT_THROW(makeTearingSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32), InputError);
  s = sheetScene();
  s.tools[0].kind = "probe";
  EXPECT_THROW(makeTearingSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32), InputError);
  s = sheetScene();  // the tearing solve is patched on the device, which Chebyshev acceleration does not support
  s.pbd.chebyshev_rho = 0.5;
  try {
    makeTearingSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
    ADD_FAILURE() << "chebyshev_rho accepted by the tearing model";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "pbd.chebyshev_rho");
  }
}

TEST(TearingSimulation, TearingSectionSetsCriterionMaterialAndRegions) {
  Scene s = sheetScene();
  TearingSceneSetup d = tearingSetupFromScene(compileScene(s));  // defaults: k = E, tau_f = 0.1 k, tresca, seed 1
  EXPECT_EQ(d.tear.criterion, TearCriterion::TrescaBonds);
  EXPECT_EQ(d.tear.seed, 1u);
  EXPECT_DOUBLE_EQ(d.sheet.k[0], 1.5e3);
  EXPECT_DOUBLE_EQ(d.sheet.tau_f[0], 150.0);
  s.tearing.criterion = "traditional";
  s.tearing.k_pa = 4e3;
  s.tearing.tau_f_pa = 300;
  s.tearing.break_strain = 0.35;
  s.tearing.random_range = 0.02;
  s.tearing.seed = 99;
  TearingRegionSpec r;  // the right half of the sheet (x >= 0.1) is weaker: tau_f only
  r.min = Vec3d(0.1, -1, -1);
  r.max = Vec3d(1, 1, 1);
  r.tau_f_pa = 50;
  s.tearing.regions.push_back(r);
  d = tearingSetupFromScene(compileScene(s));
  EXPECT_EQ(d.tear.criterion, TearCriterion::Threshold);
  EXPECT_EQ(d.tear.seed, 99u);
  EXPECT_DOUBLE_EQ(d.tear.break_strain, 0.35);
  EXPECT_DOUBLE_EQ(d.tear.random_range, 0.02);
  int in = 0, out = 0;
  for (std::size_t i = 0; i < d.sheet.size(); ++i) {
    EXPECT_DOUBLE_EQ(d.sheet.k[i], 4e3) << i;  // the region keeps the section's k
    if (d.sheet.rest[i].x >= 0.1) {
      EXPECT_DOUBLE_EQ(d.sheet.tau_f[i], 50.0) << i;
      ++in;
    } else {
      EXPECT_DOUBLE_EQ(d.sheet.tau_f[i], 300.0) << i;
      ++out;
    }
  }
  EXPECT_GT(in, 0);
  EXPECT_GT(out, 0);
  s.tearing.criterion = "von_mises";  // a Scene built in code is checked too
  try {
    tearingSetupFromScene(compileScene(s));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "tearing.criterion");
  }
}
