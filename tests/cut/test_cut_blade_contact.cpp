// The scalpel's capsule as a contact (cutting.blade_radius_m): nodal points and spheres it covers are pushed out of
// it, exactly onto its surface for the points; nothing outside it changes; a held blade stops falling tissue.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "host/scene/scene_compile.h"
#include "host/sim/dissection_simulation.h"
#include "host/sim/simulation_model.h"
#include "physics/mls_blade_contact.h"
#include "tests/support/cut_block_scene.h"

namespace inc {
namespace {

constexpr double kDt = 1.0 / 60.0;

double segmentDistance(const Vec3d& x, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  double t = dot(x - a, ab) / norm2(ab);
  t = std::min(1.0, std::max(0.0, t));
  return norm(x - (a + ab * t));
}

// A blade held still along the z axis from z = -1 to 1 m, radius 1 cm, over 0.01 s in 4 substeps.
MlsBladeContact<double> staticBladeAlongZ() {
  MlsBladeContact<double> c;
  c.a0 = c.a1 = Vec3d(0, 0, -1);
  c.b0 = c.b1 = Vec3d(0, 0, 1);
  c.radius = 0.01;
  c.duration = 0.01;
  c.substeps = 4;
  return c;
}

// A static blade along z (radius 1 cm): a covered point lands on the capsule along its own direction from the axis
// (1e-15 m), loses only the velocity into the blade; a point on the axis lands on the surface too; a point outside,
// or moving out, keeps its state bit for bit. Velocities to 1e-14 m/s (the normal's rounding).
TEST(MlsBladeContact, CoveredPointsLandOnTheCapsuleAndKeepTheirTangentialVelocity) {
  MlsBladeContact<double> c = staticBladeAlongZ();
  const Vec3d rest(0.001, 0.002, 0.3);
  Vec3d u(0.003, 0.001, 0.0), v(-1.0, 0.5, 0.2);  // x = (0.004, 0.003, 0.3): 5 mm from the axis
  mlsBladeContactAt(c, rest, u, v, 2);
  const Vec3d x = rest + u, n(0.8, 0.6, 0.0);
  EXPECT_NEAR(segmentDistance(x, c.a0, c.b0), 0.01, 1e-15);
  EXPECT_NEAR(x.x, 0.008, 1e-15);
  EXPECT_NEAR(x.y, 0.006, 1e-15);
  EXPECT_NEAR(x.z, 0.3, 1e-15);
  EXPECT_NEAR(dot(v, n), 0.0, 1e-14);               // into the blade: removed (it was -0.5)
  EXPECT_NEAR(v.x * 0.6 - v.y * 0.8, -1.0, 1e-14);  // tangential: kept
  EXPECT_NEAR(v.z, 0.2, 1e-14);
  Vec3d u_axis(-0.001, -0.002, 0.0), v_axis(0, 0, 0);  // exactly on the axis
  mlsBladeContactAt(c, rest, u_axis, v_axis, 1);
  EXPECT_NEAR(segmentDistance(rest + u_axis, c.a0, c.b0), 0.01, 1e-15);
  Vec3d u_out(0.02, 0.0, 0.0), v_out(-3.0, 1.0, 0.0);  // 21 mm away: untouched
  mlsBladeContactAt(c, rest, u_out, v_out, 3);
  EXPECT_EQ(u_out.x, 0.02);
  EXPECT_EQ(v_out.x, -3.0);
  Vec3d u_leaving(0.003, 0.001, 0.0), v_leaving(2.0, 0.0, 0.0);  // covered but moving out: keeps its velocity
  mlsBladeContactAt(c, rest, u_leaving, v_leaving, 2);
  EXPECT_EQ(v_leaving.x, 2.0);
  EXPECT_EQ(v_leaving.y, 0.0);
}

// Coulomb friction on a static blade along z (radius 1 cm): a covered point moving into it at 0.5 m/s and along it
// at 1 m/s loses mu * 0.5 m/s of its tangential speed (mu 0.4: 1.0 -> 0.8 m/s, its direction kept), and with mu 3
// (mu dv_n >= |v_t|) it sticks: it moves with the blade, static or moving (1e-14 m/s). mu 0 is the frictionless
// contact bit for bit; a point outside is untouched whatever mu.
TEST(MlsBladeContact, FrictionTakesAtMostMuTimesTheNormalChange) {
  MlsBladeContact<double> c = staticBladeAlongZ();
  const Vec3d rest(0.001, 0.002, 0.3), u0(0.003, 0.001, 0.0);  // x = (0.004, 0.003, 0.3): normal n = (0.8, 0.6, 0)
  const Vec3d v0(-1.0, 0.5, 0.0);                              // -0.5 n + 1.0 t with t = (-0.6, 0.8, 0)
  Vec3d u = u0, v = v0, u_free = u0, v_free = v0;
  c.friction = 0.4;
  mlsBladeContactAt(c, rest, u, v, 2);
  EXPECT_NEAR(v.x, -0.6 * 0.8, 1e-14);
  EXPECT_NEAR(v.y, 0.8 * 0.8, 1e-14);
  EXPECT_NEAR(v.z, 0.0, 1e-14);
  c.friction = 0.0;
  mlsBladeContactAt(c, rest, u_free, v_free, 2);
  EXPECT_EQ(u.x, u_free.x);  // friction changes velocities only
  EXPECT_EQ(u.y, u_free.y);
  EXPECT_NEAR(v_free.x, -0.6, 1e-14);
  EXPECT_NEAR(v_free.y, 0.8, 1e-14);
  c.friction = 3.0;
  Vec3d us = u0, vs = v0;
  mlsBladeContactAt(c, rest, us, vs, 2);
  EXPECT_NEAR(norm(vs), 0.0, 1e-14);
  c.a1 = c.a0 + Vec3d(0, 0, 0.002);  // the blade moving along its own axis at 0.2 m/s: |v_t| = 1.02 <= 3 x 0.5,
  c.b1 = c.b0 + Vec3d(0, 0, 0.002);  // so the point sticks and goes with it
  us = u0;
  vs = v0;
  mlsBladeContactAt(c, rest, us, vs, 4);
  EXPECT_NEAR(norm(vs - Vec3d(0, 0, 0.2)), 0.0, 1e-14);
  Vec3d u_out(0.02, 0.0, 0.0), v_out(-3.0, 1.0, 0.0);
  mlsBladeContactAt(c, rest, u_out, v_out, 3);
  EXPECT_EQ(v_out.x, -3.0);
  EXPECT_EQ(v_out.y, 1.0);
}

// A blade moving along +x at 1 m/s over 4 substeps: substep j (remaining 4 - j) sees the segment at (j + 1) / 4 of
// its motion, and a point it pushes from behind leaves with at least the blade's normal speed.
TEST(MlsBladeContact, MovingBladeIsWhereItsSubstepPutsItAndCarriesThePointsItPushes) {
  MlsBladeContact<double> c;
  c.a0 = Vec3d(0, 0, -1);
  c.b0 = Vec3d(0, 0, 1);
  c.a1 = Vec3d(0.004, 0, -1);
  c.b1 = Vec3d(0.004, 0, 1);
  c.radius = 0.001;
  c.duration = 0.004;
  c.substeps = 4;
  for (int j = 0; j < 4; ++j) {
    Vec3d u(0.0015 + 0.001 * j, 0.0, 0.0), v(0, 0, 0);  // just ahead of where the blade is at the substep's end
    mlsBladeContactAt(c, Vec3d(), u, v, 4 - j);
    EXPECT_NEAR(u.x, 0.001 * (j + 1) + 0.001, 1e-15) << j;
    EXPECT_NEAR(v.x, 1.0, 1e-12) << j;
  }
}

// A 6 x 4 x 3 cm block cut straight through by a vertical blade (float64, CPU, no gravity): with a 2 mm blade
// capsule no nodal point is inside the blade at the end of any frame of the stroke (1e-9 relative), the mass stays
// exact (1e-9); without it the same stroke leaves points inside, so the test sees the contact.
Scene cutBlock(double blade_radius) {
  Scene s = cuttest::cutBlockScene(0.25);
  s.file = "<test:blade_contact>";
  s.cutting.blade_radius_m = blade_radius;
  return s;
}

double closestPointToBlade(SimulationModel& sim, double t) {
  RenderLayers layers;
  sim.renderLayers(layers);
  const double x = -0.05 + 0.1 * (t - 0.05) / 0.2;
  double d = 1e9;
  for (const Vec3d& p : layers.nodal_points)
    d = std::min(d, segmentDistance(p, Vec3d(x, 0.002, -0.04), Vec3d(x, 0.002, 0.04)));
  return layers.nodal_points.empty() ? 1e9 : d;
}

TEST(CutBladeContact, NoNodalPointInsideTheBladeWhileItCuts) {
  const double r = 0.002;
  for (const double radius : {r, 0.0}) {
    auto sim = makeDissectionSimulation(compileScene(cutBlock(radius)), BackendKind::Cpu, Precision::Float64);
    double closest = 1e9, m0 = 0;
    int frames_with_points = 0;
    for (int f = 0; f < 14; ++f) {
      const FrameReport rep = sim->advance(kDt);
      ASSERT_TRUE(rep.finite) << f;
      if (f == 0) m0 = rep.counters.at("mass_kg");
      EXPECT_NEAR(rep.counters.at("mass_kg") / m0, 1.0, 1e-9) << f;
      if (rep.counters.at("nodal_points") == 0) continue;
      ++frames_with_points;
      closest = std::min(closest, closestPointToBlade(*sim, (f + 1) * kDt));
    }
    EXPECT_GT(frames_with_points, 5);
    if (radius > 0) {
      EXPECT_GE(closest, r * (1 - 1e-9));
    } else {
      EXPECT_LT(closest, 0.5 * r);  // without the contact the blade passes through points
    }
  }
}

// A horizontal blade held still 3 cm under a falling block (it never enters the block's rest configuration, so it
// cuts nothing): with a 1 mm capsule the spheres come to rest on it, no sphere's ball into the blade by more than
// 1e-9 m in any frame; without it the block falls through (the balls nearest the blade's line, 5 mm off it, reach
// 2.5 mm into it). The blade does not switch on the local volume preservation (the scene has it) as a grasper would.
TEST(CutBladeContact, HeldBladeStopsFallingTissue) {
  for (const double radius : {0.001, 0.0}) {
    Scene s = cutBlock(radius);
    s.solver.gravity = Vec3d(0, 0, -9.81);
    s.tools[0].path = {{0.0, Vec3d(0.0, 0.0, -0.03), Vec3d(0, 1, 0)}, {0.5, Vec3d(0.0, 0.0, -0.03), Vec3d(0, 1, 0)}};
    auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
    const double rs = 0.0075;
    double deepest = 0;
    for (int f = 0; f < 24; ++f) {
      const FrameReport rep = sim->advance(kDt);
      ASSERT_TRUE(rep.finite) << f;
      EXPECT_EQ(rep.counters.at("volume_active"), 0.0) << f;  // a contact, not a squeezing tool (pbd volume on)
      std::vector<Vec3d> x;
      sim->currentPositions(x);
      for (const Vec3d& p : x)
        deepest = std::max(deepest, rs + radius - segmentDistance(p, Vec3d(0, -0.04, -0.03), Vec3d(0, 0.04, -0.03)));
    }
    if (radius > 0) {
      EXPECT_LT(deepest, 1e-9);   // measured 1.7e-18 m: the contacts are exact projections
      EXPECT_GT(deepest, -1e-9);  // and the block does rest on the blade
    } else {
      EXPECT_GT(deepest, 0.002);
    }
  }
}

// The blade's friction on the nodal points it cuts through (a vertical 2 mm capsule moving along +x through the
// block, float64, no gravity): points sliding along its sides are dragged along its motion. The two runs have the
// same points (the conversions depend on the sweep alone); with mu = 1 they lie further along +x than without
// friction after 12 frames: measured 10.2 mm on average, 11.8 mm within 2 mm of the capsule (up to 20.3 mm; the
// spheres the capsule pushes slide on it with the same mu).
// Bounds: over 2 mm on average, the points at the blade's sides more than the mean.
TEST(CutBladeContact, FrictionDragsTheCutTissueAlongTheBlade) {
  std::vector<Vec3d> points[2];
  for (int k = 0; k < 2; ++k) {
    Scene s = cutBlock(0.002);
    s.cutting.blade_friction = k == 0 ? 0.0 : 1.0;
    auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
    for (int f = 0; f < 12; ++f) ASSERT_TRUE(sim->advance(kDt).finite) << f;
    RenderLayers layers;
    sim->renderLayers(layers);
    points[k] = layers.nodal_points;
  }
  ASSERT_FALSE(points[0].empty());
  ASSERT_EQ(points[0].size(), points[1].size());
  double mean = 0, side = 0, side_max = 0;
  int at_side = 0;
  for (std::size_t i = 0; i < points[0].size(); ++i) {
    const double dx = points[1][i].x - points[0][i].x;
    mean += dx / double(points[0].size());
    if (std::abs(points[0][i].y - 0.002) < 0.004) {  // within 2 mm of the blade's capsule surface
      side += dx;
      side_max = std::max(side_max, dx);
      ++at_side;
    }
  }
  ASSERT_GT(at_side, 20);
  std::printf(
      "[blade friction] mu 1 against 0 after 12 frames: mean %.1f mm, within 2 mm of the blade %.1f mm (max %.1f)\n",
      mean * 1e3, side / at_side * 1e3, side_max * 1e3);
  EXPECT_GT(mean, 0.002);
  EXPECT_GT(side / at_side, mean);
  EXPECT_LT(side_max, 0.05);  // dragged, not flung: within the blade's 5 cm of travel over the frames
}
}  // namespace
}  // namespace inc
