// DissectionSimulation: a scripted straight cut through a block separates it, keeps it at rest and closed.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <utility>

#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "host/sim/dissection_simulation.h"
#include "model/input_error.h"
#include "tests/support/cut_block_scene.h"
#include "tests/support/repo_paths.h"

namespace inc {
namespace {

// A 6 x 4 x 3 cm block of 1 cm metaballs without gravity; a scalpel with an 8 cm vertical blade crosses it
// along x in the plane y = 2 mm during 0.05 s .. 0.15 s.
Scene blockCutScene() {
  Scene s = cuttest::dissectionBlock("<test:block_cut>");
  s.tools = {cuttest::straightScalpel(0.05, 0.15)};
  return s;
}

TEST(CutDissection, StraightCutSeparatesTheBlockAtRestWithAClosedSurface) {
  auto sim = makeDissectionSimulation(compileScene(blockCutScene()), BackendKind::Cpu, Precision::Float64);
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

// The side y < 2 mm is held (every sphere on it is fixed), the other falls under gravity once cut free: the held
// piece's surface must not move at all (its vertices bind only to its own, fixed spheres), the free piece falls.
TEST(CutDissection, NoSkinWeightCrossesTheCut) {
  Scene s = blockCutScene();
  s.solver.gravity = Vec3d(0, 0, -9.81);
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(1, 0.002, 1)}};
  auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  for (int f = 0; f < 9; ++f) ASSERT_TRUE(sim->advance(1.0 / 60.0).finite);
  ASSERT_EQ(sim->advance(1.0 / 60.0).counters["cuts_applied"], 1.0);
  TriangleMesh at_cut, later;
  ASSERT_TRUE(sim->currentSurface(at_cut));
  for (int f = 0; f < 20; ++f) ASSERT_TRUE(sim->advance(1.0 / 60.0).finite);
  ASSERT_TRUE(sim->currentSurface(later));
  ASSERT_EQ(at_cut.vertices.size(), later.vertices.size());
  // The two surface pieces (connected components over shared vertices); the held one has its centroid at y < 2 mm
  // (the free one sagged before the cut, so single vertices may have crossed y = 2 mm).
  std::vector<int> comp(later.vertices.size());
  for (std::size_t v = 0; v < comp.size(); ++v) comp[v] = int(v);
  const auto find = [&](int x) {
    while (comp[x] != x) x = comp[x] = comp[comp[x]];
    return x;
  };
  for (const auto& t : later.triangles) {
    comp[find(t[0])] = find(t[1]);
    comp[find(t[1])] = find(t[2]);
  }
  std::map<int, std::pair<double, int>> centroid_y;
  for (std::size_t v = 0; v < comp.size(); ++v) {
    auto& c = centroid_y[find(int(v))];
    c.first += at_cut.vertices[v].y;
    c.second += 1;
  }
  ASSERT_EQ(centroid_y.size(), 2u);
  int held = 0, fell = 0;
  for (std::size_t v = 0; v < later.vertices.size(); ++v) {
    const auto& c = centroid_y[find(int(v))];
    const double moved = norm(later.vertices[v] - at_cut.vertices[v]);
    if (c.first / c.second < 0.002) {
      ASSERT_LT(moved, 1e-12) << "held-side vertex " << v;
      ++held;
    } else {
      EXPECT_LT(later.vertices[v].z, at_cut.vertices[v].z - 1e-3) << "free-side vertex " << v;
      ++fell;
    }
  }
  EXPECT_GT(held, 50);
  EXPECT_GT(fell, 50);
}

TEST(CutDissection, MissingScalpelOrCuttingFlagIsAnInputError) {
  Scene s = blockCutScene();
  s.tools.clear();
  EXPECT_THROW(makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64), InputError);
  s = blockCutScene();
  s.models.cutting = false;
  EXPECT_THROW(makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64), InputError);
  s = blockCutScene();
  s.tools[0].path.resize(1);
  EXPECT_THROW(makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64), InputError);
}

// The shipped liver scene: a curved scalpel path cuts the right tip off (the sphere graph splits in two), the
// nodal points exist only while the blade is in, the mass is kept (float32: 1e-5), and the grasper then takes
// the tip and pulls the cut open by more than 1 cm. To stay fast the test samples the converted spheres with 2
// cells per diameter (8 points each; the scene asks for 3), exchanges twice per frame (the scene: 4) and takes 5
// PBD iterations (the scene: 10); everything else is the scene file's.
TEST(CutDissection, LiverCutSceneCutsACurvedPathAndTheGrasperOpensIt) {
  Scene s = loadSceneFile(test::sourcePath("scenes/liver_cut.json"));
  s.cutting.samples_per_diameter = 2;
  s.cutting.exchanges_per_frame = 2;
  s.pbd.iterations = 5;
  auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  FrameReport rep = sim->advance(s.solver.frame_dt);
  const double m0 = rep.counters["mass_kg"];
  double points_max = 0, grasped = 0, disp_before_grasp = 0;
  for (int f = 1; f < 57; ++f) {  // to 0.95 s: the cut (0.1 .. 0.6 s) and most of the pull (0.7 .. 1.1 s)
    rep = sim->advance(s.solver.frame_dt);
    ASSERT_TRUE(rep.finite) << f;
    EXPECT_NEAR(rep.counters["mass_kg"] / m0, 1.0, 1e-5) << f;
    points_max = std::max(points_max, rep.counters["nodal_points"]);
    grasped = std::max(grasped, rep.counters["grasped"]);
    if (f == 40) {
      EXPECT_EQ(rep.counters["cuts_applied"], 1.0);
      EXPECT_EQ(rep.counters["nodal_points"], 0.0);
      EXPECT_EQ(rep.counters["sphere_components"], 2.0);
      // Since the merge with s6-cut-surface the curved stroke also splits the surface: the tip is a piece of its own.
      EXPECT_EQ(rep.counters["surface_split"], 1.0);
      EXPECT_EQ(rep.counters["surface_components"], 2.0);
      disp_before_grasp = rep.max_displacement;
    }
  }
  EXPECT_GT(points_max, 100.0);
  EXPECT_GT(grasped, 0.0);
  EXPECT_GT(rep.max_displacement, disp_before_grasp + 0.01);
  TriangleMesh surf;
  ASSERT_TRUE(sim->currentSurface(surf));
  for (const auto& v : surf.vertices) ASSERT_TRUE(isFinite(v));
  const MeshReport m = analyzeMesh(surf);
  EXPECT_TRUE(m.closed());
  EXPECT_EQ(m.components, 2);
}

// A mouse stroke that begins while a scripted scalpel is mid-stroke takes the blade: the scripted stroke's cut so
// far is applied at the press and that stroke is over; the mouse stroke then cuts on its own. (The scripted
// stroke once went on extending a stroke that no longer existed and crashed the viewer: SIGSEGV in extendStroke.)
TEST(CutDissection, MouseStrokeDuringAScriptedStrokeTakesTheBlade) {
  const double dt = 1.0 / 60.0;
  Scene s = cuttest::cutBlockScene(0.25, false, "<test:mouse_over_scripted>");  // in the tissue from 0.05 s on
  auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  int frame = 0;
  for (; frame < 9; ++frame) ASSERT_TRUE(sim->advance(dt).finite) << frame;  // 0.15 s: the blade is halfway
  ToolEvent e = cuttest::mouseScalpel();
  const int steps = 6;
  for (int k = 0; k <= steps; ++k, ++frame) {
    e.phase = k == 0 ? ToolPhase::Press : k == steps ? ToolPhase::Release : ToolPhase::Drag;
    e.tip = Vec3d(-0.05 + 0.1 * k / steps, -0.01, 0.0);  // another plane, y = -1 cm
    ASSERT_NO_THROW(sim->applyTool(e)) << k;
    ASSERT_TRUE(sim->advance(dt).finite) << frame;
  }
  FrameReport rep;
  for (; frame < 30; ++frame) ASSERT_TRUE((rep = sim->advance(dt)).finite) << frame;  // past the script's end
  EXPECT_EQ(rep.counters.at("cuts_applied"), 2.0);  // the scripted stroke's part, then the mouse's stroke
  EXPECT_EQ(rep.counters.at("nodal_points"), 0.0);
  EXPECT_GE(rep.counters.at("sphere_components"), 2.0);  // the mouse stroke went through the block
}

}  // namespace
}  // namespace inc
