// SimulationModel::renderLayers of the models: spheres, fixed and held particles, grasp and support forces
// (balance of the weight at rest), swept surfaces and nodal points of a cut. CPU only.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "host/scene/scene_compile.h"
#include "host/sim/dissection_simulation.h"
#include "host/sim/metaball_simulation.h"
#include "host/sim/mls_simulation.h"
#include "host/sim/tearing_simulation.h"
#include "tests/support/cut_block_scene.h"

using namespace inc;

namespace {

bool inBox(const Vec3d& p, const FixedRegion& r) {
  return p.x >= r.min.x && p.x <= r.max.x && p.y >= r.min.y && p.y <= r.max.y && p.z >= r.min.z && p.z <= r.max.z;
}

// A 6 x 4 x 3 cm block of 1 cm lattice metaballs.
Scene metaballBlock() {
  Scene s;
  s.file = "<test:render_layers_block>";
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.size = Vec3d(0.06, 0.04, 0.03);
  s.geometry.spacing = 0.01;
  s.models.pbd_metaballs = true;
  s.solver.substeps = 4;
  s.pbd.iterations = 10;
  return s;
}

bool same(const Vec3d& a, const Vec3d& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

Vec3d sum(const std::vector<ForceArrow>& a, ForceArrowKind kind) {
  Vec3d s;
  for (const ForceArrow& f : a)
    if (f.kind == kind) s += f.force_n;
  return s;
}

}  // namespace

// The metaball organ reports every sphere at its centre with its radius (lattice fill: 0.75 x spacing), and
// exactly the spheres whose rest centre lies in the scene's fixed box as fixed.
TEST(RenderLayers, MetaballSpheresAndFixedSetMatchTheScene) {
  Scene s = metaballBlock();
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(-0.01, 1, 1)}};  // the x < -1 cm slab: 2 of 6 columns
  auto m = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  std::vector<Vec3d> rest;
  m->currentPositions(rest);
  for (int f = 0; f < 3; ++f) ASSERT_TRUE(m->advance(1.0 / 60.0).finite);
  RenderLayers l;
  m->renderLayers(l);
  std::vector<Vec3d> x;
  m->currentPositions(x);
  ASSERT_EQ(l.sphere_centres.size(), m->particleCount());
  ASSERT_EQ(l.sphere_radii.size(), m->particleCount());
  for (std::size_t i = 0; i < x.size(); ++i) {
    EXPECT_TRUE(same(l.sphere_centres[i], x[i])) << i;
    EXPECT_NEAR(l.sphere_radii[i], 0.75 * 0.01, 1e-9);  // no tool near: volume preservation leaves radii
  }
  std::set<std::int32_t> expected;
  for (std::size_t i = 0; i < rest.size(); ++i)
    if (inBox(rest[i], s.fixed[0])) expected.insert(std::int32_t(i));
  EXPECT_EQ(expected.size(), 2u * 4u * 3u);
  EXPECT_EQ(std::set<std::int32_t>(l.fixed_ids.begin(), l.fixed_ids.end()), expected);
  ASSERT_EQ(l.fixed_points.size(), l.fixed_ids.size());
  for (std::size_t k = 0; k < l.fixed_ids.size(); ++k)
    EXPECT_TRUE(same(l.fixed_points[k], rest[std::size_t(l.fixed_ids[k])]));
  EXPECT_TRUE(l.held_ids.empty());
  EXPECT_TRUE(l.forces.empty());
  EXPECT_TRUE(l.swept_surface.triangles.empty());
}

// A free block hanging from the mouse grasp under gravity: at rest the attachments carry its whole weight, so
// the tool's arrow (the tissue's pull on the tool) is M g and the per-sphere forces sum to -M g. XPBD with
// Gauss-Seidel (every projection conserves momentum), float64 (the attachment stretch is ~1e-8 m per sphere).
TEST(RenderLayers, MetaballGraspForceCarriesTheWeightAtRest) {
  Scene s = metaballBlock();
  s.pbd.solver = "gauss_seidel";
  s.material.damping_per_s = 8.0;
  auto m = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  ToolEvent e;
  e.kind = ToolKind::Grasp;
  e.phase = ToolPhase::Press;
  e.tip = Vec3d(0, 0, 0.015);  // the middle of the top face
  e.radius_m = 0.012;
  const ToolResult r = m->applyTool(e);
  ASSERT_GT(r.grasped, 0);
  for (int f = 0; f < 100; ++f) ASSERT_TRUE(m->advance(1.0 / 60.0).finite);
  const FrameReport rep = m->advance(1.0 / 60.0);
  EXPECT_LT(rep.kinetic_energy, 1e-9);  // at rest
  RenderLayers l;
  m->renderLayers(l);
  EXPECT_EQ(int(l.held_ids.size()), r.grasped);
  ASSERT_EQ(l.held_points.size(), l.held_ids.size());
  const double mass = 1060.0 * 1e-6 * double(m->particleCount());  // density x spacing^3 per sphere
  const Vec3d weight = s.solver.gravity * mass;
  const Vec3d tool = sum(l.forces, ForceArrowKind::Tool), held = sum(l.forces, ForceArrowKind::Particle);
  EXPECT_EQ(std::count_if(l.forces.begin(), l.forces.end(),
                          [](const ForceArrow& a) { return a.kind == ForceArrowKind::Tool; }),
            1);
  // Measured 4e-12 of the weight (2026-11-25): the momentum argument is exact once the block is at rest.
  EXPECT_NEAR(norm(tool - weight), 0.0, 1e-6 * norm(weight)) << tool.z << " vs " << weight.z;
  EXPECT_NEAR(norm(held + tool), 0.0, 1e-12 * norm(weight));
  for (const ForceArrow& a : l.forces) {
    if (a.kind == ForceArrowKind::Tool) {
      EXPECT_TRUE(same(a.origin, e.tip));
    }
  }
}

// The MLS cantilever lifted at its tip by a scripted grasper, at rest under gravity: the clamp's and the
// grasp's forces on the pinned particles carry the weight (sum F_fixed + sum F_held + M g = 0), the tool's
// arrow is minus the grasp's share, and the tissue pulls the lifting tool down. Every particle is a nodal point;
// the fixed set is the clamp box.
TEST(RenderLayers, MlsClampAndGraspForcesBalanceTheWeightAtRest) {
  Scene s;
  s.file = "<test:render_layers_beam>";
  s.geometry.kind = GeometrySpec::Kind::Beam;
  s.geometry.center = Vec3d(0.04, 0, 0);
  s.geometry.size = Vec3d(0.08, 0.02, 0.02);
  s.geometry.spacing = 0.005;
  s.material.youngs_modulus_pa = 2e5;
  s.material.poisson_ratio = 0.4;
  s.material.density_kg_m3 = 1060;
  s.material.damping_per_s = 80;  // about critical for the first bending mode (omega ~ 44 rad/s)
  s.models.mls = true;
  s.fixed = {{Vec3d(-0.001, -0.011, -0.011), Vec3d(0.0051, 0.011, 0.011)}};
  ToolSpec g;
  g.name = "forceps";
  g.kind = "grasper";
  g.radius = 0.006;
  g.path = {{0.0, Vec3d(0.0775, 0, 0), Vec3d(0, 0, -1)}, {0.1, Vec3d(0.0775, 0, 0.003), Vec3d(0, 0, -1)}};
  s.tools = {g};
  auto m = makeMlsSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  std::vector<Vec3d> rest;
  m->currentPositions(rest);
  for (int f = 0; f < 45; ++f) ASSERT_TRUE(m->advance(1.0 / 60.0).finite);
  RenderLayers l;
  m->renderLayers(l);
  std::vector<Vec3d> x;
  m->currentPositions(x);
  ASSERT_EQ(l.nodal_points.size(), x.size());
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_TRUE(same(l.nodal_points[i], x[i])) << i;
  std::set<std::int32_t> clamp;
  for (std::size_t i = 0; i < rest.size(); ++i)
    if (inBox(rest[i], s.fixed[0])) clamp.insert(std::int32_t(i));
  EXPECT_EQ(std::set<std::int32_t>(l.fixed_ids.begin(), l.fixed_ids.end()), clamp);
  ASSERT_FALSE(l.held_ids.empty());
  Vec3d fixed_sum, held_sum, tool;
  const std::set<std::int32_t> held(l.held_ids.begin(), l.held_ids.end());
  std::size_t k_fixed = 0, k_held = 0;
  for (const ForceArrow& a : l.forces) {
    if (a.kind == ForceArrowKind::Tool) {
      tool += a.force_n;
      EXPECT_NEAR(norm(a.origin - Vec3d(0.0775, 0, 0.003)), 0.0, 1e-12);
    } else if (k_fixed < l.fixed_ids.size() && same(a.origin, l.fixed_points[k_fixed])) {
      fixed_sum += a.force_n;
      ++k_fixed;
    } else {
      held_sum += a.force_n;
      ++k_held;
    }
  }
  EXPECT_EQ(k_fixed, l.fixed_ids.size());
  EXPECT_EQ(k_held, l.held_ids.size());
  const Vec3d weight = s.solver.gravity * (1060.0 * 0.005 * 0.005 * 0.005 * double(x.size()));
  // Measured 7e-13 of the weight (2026-11-25): the elastic forces sum to zero, the beam is at rest.
  EXPECT_NEAR(norm(fixed_sum + held_sum + weight), 0.0, 1e-6 * norm(weight))
      << fixed_sum.z << " + " << held_sum.z << " vs " << weight.z;
  EXPECT_NEAR(norm(tool + held_sum), 0.0, 1e-12 * norm(weight));
  EXPECT_LT(tool.z, -0.05 * norm(weight));  // lifting the tip bends the beam: it pulls the tool down
}

// The dissection block cut by a mouse stroke on the plane y = 2 mm: while the stroke runs its swept surface
// is reported on that plane over the stroke's extent, and the stroke's nodal points where the MLS solver has them
// (as many as the nodal_points counter, all within two sphere radii of the plane). With the y < 2 mm half fixed
// and gravity on, the free half's points fall while the held half's stay. Once released, the points are re-packed
// and go back to zero (none reported; since the merge of s6-cut-mls the nodal points live only while the blade is
// in the tissue, where before they were the last cut's, skinned) and the applied cut's swept surface is.
TEST(RenderLayers, DissectionSweptSurfaceAndNodalPointsFollowTheCut) {
  Scene s = cuttest::dissectionBlock("<test:render_layers_cut>", true);
  s.cutting.samples_per_diameter = 3;
  s.cutting.exchanges_per_frame = 2;
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(1, 0.002, 1)}};
  s.tools = {cuttest::parkedScalpel()};  // the scene's scripted scalpel never runs here
  auto m = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  RenderLayers l;
  m->renderLayers(l);
  EXPECT_TRUE(l.swept_surface.triangles.empty());
  EXPECT_TRUE(l.nodal_points.empty());
  EXPECT_EQ(l.sphere_centres.size(), m->particleCount());
  ToolEvent e;
  e.kind = ToolKind::Cut;
  e.axis = Vec3d(0, 0, -1);
  e.blade_length_m = 0.08;
  for (int k = 0; k <= 3; ++k) {  // press and three drags: -5 cm .. +2.5 cm, not released
    e.phase = k == 0 ? ToolPhase::Press : ToolPhase::Drag;
    e.tip = Vec3d(-0.05 + 0.025 * k, 0.002, 0.0);
    ASSERT_TRUE(m->applyTool(e).supported);
  }
  m->renderLayers(l);
  EXPECT_EQ(l.sphere_centres.size(), m->particleCount());  // the cut spheres left the PBD model
  ASSERT_EQ(l.swept_surface.triangles.size(), 6u);         // 3 quads of the strip
  double xmin = 1, xmax = -1;
  for (const Vec3d& v : l.swept_surface.vertices) {
    EXPECT_NEAR(v.y, 0.002, 1e-9);  // nothing moved yet: rest = current
    xmin = std::min(xmin, v.x);
    xmax = std::max(xmax, v.x);
  }
  EXPECT_NEAR(xmin, -0.05, 1e-9);
  EXPECT_NEAR(xmax, 0.025, 1e-9);
  e.tip = Vec3d(0.05, 0.002, 0.0);  // a fourth drag: through the block, still in the tissue
  ASSERT_TRUE(m->applyTool(e).supported);
  const FrameReport first = m->advance(1e-6);  // a negligible step: the counters of the stroke
  ASSERT_TRUE(first.finite);
  RenderLayers cut;
  m->renderLayers(cut);
  EXPECT_EQ(double(cut.nodal_points.size()), first.counters.at("nodal_points"));
  ASSERT_FALSE(cut.nodal_points.empty());
  // A nodal point lies in a converted (cut or interface) sphere, whose centre is within 1.5 spacings of the plane.
  for (const Vec3d& p : cut.nodal_points) EXPECT_LT(std::fabs(p.y - 0.002), 0.015 + 0.0075 + 1e-6);
  EXPECT_EQ(cut.swept_surface.triangles.size(), 8u);  // the stroke so far: 4 quads
  for (int f = 0; f < 6; ++f) ASSERT_TRUE(m->advance(1.0 / 60.0).finite);
  RenderLayers later;
  m->renderLayers(later);
  ASSERT_EQ(later.nodal_points.size(), cut.nodal_points.size());  // no conversion since: the same points
  int held_side = 0, free_side = 0;
  for (std::size_t i = 0; i < cut.nodal_points.size(); ++i) {
    const double dz = later.nodal_points[i].z - cut.nodal_points[i].z;
    if (cut.nodal_points[i].y < 0.002) {
      EXPECT_NEAR(dz, 0.0, 1e-3) << i;  // points of fixed spheres
      ++held_side;
    } else {
      EXPECT_LT(dz, -0.02) << i;  // falls with the free half (~5 cm in 6 frames)
      ++free_side;
    }
  }
  EXPECT_GT(held_side, 0);
  EXPECT_GT(free_side, 0);
  e.phase = ToolPhase::Release;
  ASSERT_TRUE(m->applyTool(e).cut_applied);
  const FrameReport after = m->advance(1e-6);
  ASSERT_TRUE(after.finite);
  EXPECT_EQ(after.counters.at("nodal_points"), 0.0);
  EXPECT_EQ(after.counters.at("nodal_points_last_cut"), double(cut.nodal_points.size()));
  RenderLayers done;
  m->renderLayers(done);
  EXPECT_TRUE(done.nodal_points.empty());
  EXPECT_EQ(done.sphere_centres.size(), m->particleCount());
  EXPECT_EQ(done.swept_surface.triangles.size(), 8u);  // the applied cut's strip
}

// The tearing sheet: the particles of its fixed strip and those its grasper holds.
TEST(RenderLayers, TearingSheetFixedAndHeldParticles) {
  Scene s;
  s.file = "<test:render_layers_sheet>";
  s.models.tearing = true;
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.center = Vec3d(0.1, 0.05, 0);
  s.geometry.size = Vec3d(0.2, 0.1, 0.002);
  s.geometry.spacing = 0.01;
  s.material.youngs_modulus_pa = 1.5e3;
  s.material.density_kg_m3 = 1100;
  s.pbd.stretch_compliance = 2e-4;
  s.solver.gravity = Vec3d(0, 0, 0);
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(0.001, 1, 1)}};
  ToolSpec g;
  g.name = "grasper";
  g.kind = "grasper";
  g.radius = 0.004;
  g.length = 0.1;
  g.path = {{0.0, Vec3d(0.2, 0.0, 0), Vec3d(0, 1, 0)}, {0.25, Vec3d(0.22, 0.0, 0), Vec3d(0, 1, 0)}};
  s.tools = {g};
  auto m = makeTearingSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  std::vector<Vec3d> rest;
  m->currentPositions(rest);
  m->advance(1.0 / 60.0);
  RenderLayers l;
  m->renderLayers(l);
  std::vector<Vec3d> x;
  m->currentPositions(x);
  std::set<std::int32_t> fixed, held;
  for (std::size_t i = 0; i < rest.size(); ++i) {
    if (inBox(rest[i], s.fixed[0])) fixed.insert(std::int32_t(i));
    if (std::fabs(rest[i].x - 0.2) < 1e-9) held.insert(std::int32_t(i));  // the grasper's blade: the x = 0.2 m edge
  }
  EXPECT_EQ(fixed.size(), 11u);
  EXPECT_EQ(std::set<std::int32_t>(l.fixed_ids.begin(), l.fixed_ids.end()), fixed);
  EXPECT_EQ(std::set<std::int32_t>(l.held_ids.begin(), l.held_ids.end()), held);
  for (std::size_t k = 0; k < l.held_ids.size(); ++k)
    EXPECT_TRUE(same(l.held_points[k], x[std::size_t(l.held_ids[k])]));
  EXPECT_TRUE(l.forces.empty());
}
