// DissectionSimulation: a scripted straight cut through a block separates it, keeps it at rest and closed.
#include <gtest/gtest.h>

#include <cmath>

#include "host/dissection_simulation.h"
#include "host/input_error.h"
#include "host/scene_loader.h"

namespace inc {
namespace {

// A 6 x 4 x 3 cm block of 1 cm metaballs without gravity; a scalpel with an 8 cm vertical blade crosses it
// along x in the plane y = 2 mm during 0.05 s .. 0.15 s.
Scene blockCutScene() {
  Scene s;
  s.file = "<test:block_cut>";
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.size = Vec3d(0.06, 0.04, 0.03);
  s.geometry.spacing = 0.01;
  s.models.pbd_metaballs = true;
  s.models.cutting = true;
  s.solver.gravity = Vec3d(0, 0, 0);
  s.solver.substeps = 2;
  s.pbd.iterations = 5;
  ToolSpec t;
  t.name = "scalpel";
  t.kind = "scalpel";
  t.length = 0.08;
  t.path = {{0.05, Vec3d(-0.05, 0.002, 0.0), Vec3d(0, 0, 1)}, {0.15, Vec3d(0.05, 0.002, 0.0), Vec3d(0, 0, 1)}};
  s.tools = {t};
  return s;
}

TEST(CutDissection, StraightCutSeparatesTheBlockAtRestWithAClosedSurface) {
  auto sim = makeDissectionSimulation(blockCutScene(), BackendKind::Cpu, Precision::Float64);
  const std::size_t n0 = sim->particleCount();
  FrameReport rep;
  double pending_max = 0;
  for (int f = 0; f < 14; ++f) {
    rep = sim->advance(1.0 / 60.0);
    ASSERT_TRUE(rep.finite) << f;
    pending_max = std::max(pending_max, rep.counters["cut_spheres_pending"]);
  }
  EXPECT_GT(pending_max, 0.0);
  EXPECT_EQ(rep.counters["cuts_applied"], 1.0);
  EXPECT_EQ(rep.counters["surface_split"], 1.0);
  EXPECT_GT(rep.counters["nodal_points_last_cut"], 0.0);
  EXPECT_NE(sim->particleCount(), n0);
  // Without gravity or contact the re-packed organ is at its (new) rest state: no spurious motion (1e-9 m).
  EXPECT_LT(rep.max_displacement, 1e-9);
  EXPECT_LT(rep.kinetic_energy, 1e-15);
  TriangleMesh surf;
  ASSERT_TRUE(sim->currentSurface(surf));
  const MeshReport m = analyzeMesh(surf);
  EXPECT_TRUE(m.closed());
  EXPECT_EQ(m.inconsistent_edges, 0);
  EXPECT_EQ(m.degenerate_triangles, 0);
  EXPECT_EQ(m.components, 2);
  EXPECT_NEAR(m.signed_volume, 0.06 * 0.04 * 0.03, 1e-9 * 0.06 * 0.04 * 0.03);
  for (const auto& v : surf.vertices) EXPECT_TRUE(isFinite(v));
}

TEST(CutDissection, MissingScalpelOrCuttingFlagIsAnInputError) {
  Scene s = blockCutScene();
  s.tools.clear();
  EXPECT_THROW(makeDissectionSimulation(s, BackendKind::Cpu, Precision::Float64), InputError);
  s = blockCutScene();
  s.models.cutting = false;
  EXPECT_THROW(makeDissectionSimulation(s, BackendKind::Cpu, Precision::Float64), InputError);
  s = blockCutScene();
  s.tools[0].path.resize(1);
  EXPECT_THROW(makeDissectionSimulation(s, BackendKind::Cpu, Precision::Float64), InputError);
}

TEST(CutDissection, LiverCutSceneRunsAndSplitsTheSurface) {
  const Scene s = loadSceneFile(std::string(INCISION_SOURCE_DIR) + "/scenes/liver_cut.json");
  auto sim = makeDissectionSimulation(s, BackendKind::Cpu, Precision::Float32);
  FrameReport rep;
  for (int f = 0; f < 38; ++f) {  // past the end of the cut at 0.6 s
    rep = sim->advance(s.solver.frame_dt);
    ASSERT_TRUE(rep.finite) << f;
  }
  EXPECT_EQ(rep.counters["cuts_applied"], 1.0);
  EXPECT_EQ(rep.counters["surface_split"], 1.0);
  TriangleMesh surf;
  ASSERT_TRUE(sim->currentSurface(surf));
  const MeshReport m = analyzeMesh(surf);
  EXPECT_TRUE(m.closed());
  EXPECT_EQ(m.inconsistent_edges, 0);
  EXPECT_EQ(m.components, 2);
}

}  // namespace
}  // namespace inc
