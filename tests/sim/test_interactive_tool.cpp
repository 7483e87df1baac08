// The interactive tool API (SimulationModel::applyTool): grasp & drag on the metaball organ, the MLS solid and
// the dissection model, and a mouse-drawn scalpel stroke that cuts the dissection model.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "host/scene/scene_compile.h"
#include "host/sim/dissection_simulation.h"
#include "host/sim/interactive_tool.h"
#include "host/sim/metaball_simulation.h"
#include "host/sim/mls_simulation.h"
#include "model/input_error.h"
#include "tests/support/cut_block_scene.h"

namespace inc {
namespace {

constexpr double kDt = 1.0 / 60.0;

// A 6 x 4 x 3 cm block (1 cm lattice) clamped at x < -2 cm, no gravity: what is pulled and let go springs back.
Scene blockScene(bool cutting) {
  Scene s = cuttest::dissectionBlock("<test:tool_block>");
  s.material.youngs_modulus_pa = 2.0e4;
  s.material.damping_per_s = 20.0;
  s.models.cutting = cutting;
  s.pbd.iterations = 10;
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(-0.02, 1, 1)}};
  if (cutting) s.tools = {cuttest::parkedScalpel()};  // the scripted scalpel runs long after these tests end
  return s;
}

ToolEvent grasp(ToolPhase phase, const Vec3d& tip, double radius) {
  ToolEvent e;
  e.kind = ToolKind::Grasp;
  e.phase = phase;
  e.tip = tip;
  e.radius_m = radius;
  return e;
}

// Mean displacement (from the positions at the grasp) of the particles listed.
Vec3d meanShift(const SimulationModel& m, const std::vector<Vec3d>& at_grasp, const std::vector<std::size_t>& ids) {
  std::vector<Vec3d> x;
  m.currentPositions(x);
  Vec3d s;
  for (std::size_t i : ids) s += x[i] - at_grasp[i];
  return s * (1.0 / double(ids.size()));
}

// Press at the free end, drag the tip 15 mm up over 10 frames, hold 20 frames, release and run 60 frames: the
// held region follows the tool (mean shift within `follow_tol` of 15 mm), after release it relaxes to under
// a third of it (the clamped block springs back, damped).
void graspDragRelease(SimulationModel& m, const Vec3d& tip, double reach, double follow_tol,
                      const std::vector<std::size_t>& region) {
  ASSERT_TRUE(m.toolSupport().grasp);
  std::vector<Vec3d> x0;
  m.currentPositions(x0);
  const ToolResult r = m.applyTool(grasp(ToolPhase::Press, tip, reach));
  ASSERT_TRUE(r.supported);
  ASSERT_GT(r.grasped, 0);
  const Vec3d lift(0, 0, 0.015);
  for (int f = 1; f <= 10; ++f) {
    m.applyTool(grasp(ToolPhase::Drag, tip + lift * (f / 10.0), reach));
    ASSERT_TRUE(m.advance(kDt).finite);
  }
  for (int f = 0; f < 20; ++f) ASSERT_TRUE(m.advance(kDt).finite);
  const Vec3d held = meanShift(m, x0, region);
  EXPECT_NEAR(held.z, 0.015, follow_tol);
  EXPECT_LT(std::fabs(held.x), follow_tol);
  EXPECT_LT(std::fabs(held.y), follow_tol);
  EXPECT_EQ(m.applyTool(grasp(ToolPhase::Release, tip + lift, reach)).grasped, 0);
  for (int f = 0; f < 60; ++f) ASSERT_TRUE(m.advance(kDt).finite);
  const Vec3d relaxed = meanShift(m, x0, region);
  EXPECT_LT(norm(relaxed), 0.015 / 3.0) << "released region did not relax: " << relaxed.z;
}

std::vector<std::size_t> within(const SimulationModel& m, const Vec3d& p, double r) {
  std::vector<Vec3d> x;
  m.currentPositions(x);
  std::vector<std::size_t> ids;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (norm(x[i] - p) <= r) ids.push_back(i);
  return ids;
}

// PBD organ: the grasped spheres are attached (compliance 1e-6 m/N) to targets riding on the tip: 1.5 mm.
TEST(InteractiveTool, MetaballGraspDragsTheRegionAndReleaseLetsItRelax) {
  auto m = makeMetaballSimulation(compileScene(blockScene(false)), BackendKind::Cpu, Precision::Float64);
  const Vec3d tip(0.025, 0.0, 0.01);
  const auto region = within(*m, tip, 0.006);  // the spheres nearest the tip: certainly caught (reach 6 mm + r)
  ASSERT_FALSE(region.empty());
  graspDragRelease(*m, tip, 0.006, 1.5e-3, region);
  EXPECT_FALSE(m->toolSupport().cut);
  ToolEvent cut;
  cut.kind = ToolKind::Cut;
  EXPECT_FALSE(m->applyTool(cut).supported);
}

// Dissection model: the same grasp machinery on its organ.
TEST(InteractiveTool, DissectionGraspDragsTheRegion) {
  auto m = makeDissectionSimulation(compileScene(blockScene(true)), BackendKind::Cpu, Precision::Float64);
  const Vec3d tip(0.025, 0.0, 0.01);
  graspDragRelease(*m, tip, 0.006, 1.5e-3, within(*m, tip, 0.006));
}

// MLS solid: grasped nodes are prescribed (pinned to the tool), so they follow it exactly (1e-9 m).
TEST(InteractiveTool, MlsGraspPinsAndDragsNodes) {
  Scene s = blockScene(false);
  s.models = {};
  s.models.mls = true;
  s.geometry.spacing = 0.0075;
  s.material.damping_per_s = 40.0;
  s.solver.substeps = 0;
  s.solver.safety = 0.8;
  auto m = makeMlsSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  const Vec3d tip(0.0275, 0.0025, 0.0125);
  const auto region = within(*m, tip, 0.008);
  ASSERT_FALSE(region.empty());
  graspDragRelease(*m, tip, 0.008, 1e-9, region);
}

TEST(InteractiveTool, ModelsWithoutAToolSayNotSupported) {
  struct Plain final : SimulationModel {
    std::string name() const override { return "plain"; }
    BackendKind backend() const override { return BackendKind::Cpu; }
    std::size_t particleCount() const override { return 0; }
    FrameReport advance(double) override { return {}; }
    void saveCheckpoint() override {}
    void restoreCheckpoint() override {}
    void scaleTimeStep(double) override {}
    void currentPositions(std::vector<Vec3d>& out) const override { out.clear(); }
    MemoryReport memory() const override { return {}; }
  } plain;
  EXPECT_FALSE(plain.toolSupport().grasp);
  EXPECT_FALSE(plain.toolSupport().cut);
  const ToolResult r = plain.applyTool(grasp(ToolPhase::Press, Vec3d(0, 0, 0), 0.01));
  EXPECT_FALSE(r.supported);
  EXPECT_NE(r.message.find("plain"), std::string::npos);
}

// A rigidly translated body: the rest point under a deformed point is exact (1e-12 m).
TEST(InteractiveTool, RestPointUndoesATranslation) {
  std::vector<Vec3d> rest, cur;
  for (int i = 0; i < 27; ++i) rest.emplace_back(0.01 * (i % 3), 0.01 * (i / 3 % 3), 0.01 * (i / 9));
  const Vec3d d(0.003, -0.02, 0.011);
  for (const auto& p : rest) cur.push_back(p + d);
  const Vec3d q(0.013, 0.004, -0.002);
  const Vec3d r = restPointFromCurrent(q + d, cur, rest);
  EXPECT_LT(norm(r - q), 1e-12);
}

// A stroke drawn across the block (view along -z, blade 8 cm centred on the tip at y = 2 mm, five poses)
// cuts it like the scripted scalpel: two sphere-graph components, the surface split into two closed pieces,
// cut-wall triangles flagged on the plane y = 2 mm.
TEST(InteractiveTool, MouseStrokeCutsTheDissectionModel) {
  Scene s = blockScene(true);
  s.fixed.clear();
  auto m = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  ASSERT_TRUE(m->toolSupport().cut);
  FrameReport rep = m->advance(kDt);
  EXPECT_EQ(rep.counters["sphere_components"], 1.0);
  std::vector<std::uint8_t> walls;
  m->cutWallTriangles(walls);
  EXPECT_TRUE(walls.empty() || std::count(walls.begin(), walls.end(), 1) == 0);
  ToolEvent e;
  e.kind = ToolKind::Cut;
  e.axis = Vec3d(0, 0, -1);
  e.blade_length_m = 0.08;
  for (int k = 0; k <= 4; ++k) {
    e.phase = k == 0 ? ToolPhase::Press : k == 4 ? ToolPhase::Release : ToolPhase::Drag;
    e.tip = Vec3d(-0.05 + 0.025 * k, 0.002, 0.0);
    const ToolResult r = m->applyTool(e);
    ASSERT_TRUE(r.supported);
    EXPECT_EQ(r.cut_applied, k == 4);
  }
  rep = m->advance(kDt);
  ASSERT_TRUE(rep.finite);
  EXPECT_EQ(rep.counters["cuts_applied"], 1.0);
  EXPECT_EQ(rep.counters["sphere_components"], 2.0);
  EXPECT_EQ(rep.counters["surface_split"], 1.0);
  EXPECT_EQ(rep.counters["surface_components"], 2.0);
  TriangleMesh surf;
  ASSERT_TRUE(m->currentSurface(surf));
  EXPECT_TRUE(analyzeMesh(surf).closed());
  m->cutWallTriangles(walls);
  ASSERT_EQ(walls.size(), surf.triangles.size());
  int wall_count = 0;
  for (std::size_t t = 0; t < walls.size(); ++t) {
    if (!walls[t]) continue;
    ++wall_count;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(surf.vertices[surf.triangles[t][k]].y, 0.002, 1e-6);
  }
  EXPECT_GT(wall_count, 4);  // both walls of a 6 x 3 cm section
  // A grasp held across a cut is released (the sphere indices changed).
  ASSERT_GT(m->applyTool(grasp(ToolPhase::Press, Vec3d(0.025, 0.01, 0.0), 0.006)).grasped, 0);
  for (int k = 0; k <= 1; ++k) {
    e.phase = k == 0 ? ToolPhase::Press : ToolPhase::Release;
    e.tip = Vec3d(0.012, -0.05 + 0.1 * k, 0.0);
    m->applyTool(e);
  }
  rep = m->advance(kDt);
  EXPECT_EQ(rep.counters["cuts_applied"], 2.0);
  EXPECT_EQ(rep.counters["grasped"], 0.0);
  EXPECT_GE(rep.counters["sphere_components"], 3.0)
      << rep.counters["nodal_points_last_cut"] << " nodal points, " << rep.counters["spheres"] << " spheres";
}

TEST(InteractiveTool, BadToolEventsAreInputErrors) {
  auto m = makeDissectionSimulation(compileScene(blockScene(true)), BackendKind::Cpu, Precision::Float32);
  ToolEvent e;
  e.kind = ToolKind::Cut;
  e.tip = Vec3d(0, 0, 0);
  e.blade_length_m = 0.0;
  EXPECT_THROW(m->applyTool(e), InputError);
  e.blade_length_m = 0.05;
  e.axis = Vec3d(0, 0, 0);
  EXPECT_THROW(m->applyTool(e), InputError);
  EXPECT_THROW(m->applyTool(grasp(ToolPhase::Press, Vec3d(0, 0, 0), -1.0)), InputError);
  EXPECT_THROW(m->applyTool(grasp(ToolPhase::Press, Vec3d(NAN, 0, 0), 0.01)), InputError);
}

}  // namespace
}  // namespace inc
