// The scalpel's capsule as a contact (cutting.blade_radius_m): nodal points and spheres it covers are pushed out of
// it, exactly onto its surface for the points; nothing outside it changes; a held blade stops falling tissue.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "host/dissection_simulation.h"
#include "host/simulation_model.h"
#include "physics/mls_blade_contact.h"
#include "tests/cut_block_scene.h"

namespace inc {
namespace {

constexpr double kDt = 1.0 / 60.0;

double segmentDistance(const Vec3d& x, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  double t = dot(x - a, ab) / norm2(ab);
  t = std::min(1.0, std::max(0.0, t));
  return norm(x - (a + ab * t));
}

// A static blade along z (radius 1 cm): a covered point lands on the capsule along its own direction from the axis
// (1e-15 m), loses only the velocity into the blade; a point on the axis lands on the surface too; a point outside,
// or moving out, keeps its state bit for bit. Velocities to 1e-14 m/s (the normal's rounding).
TEST(MlsBladeContact, CoveredPointsLandOnTheCapsuleAndKeepTheirTangentialVelocity) {
  MlsBladeContact<double> c;
  c.a0 = c.a1 = Vec3d(0, 0, -1);
  c.b0 = c.b1 = Vec3d(0, 0, 1);
  c.radius = 0.01;
  c.duration = 0.01;
  c.substeps = 4;
  const Vec3d rest(0.001, 0.002, 0.3);
  Vec3d u(0.003, 0.001, 0.0), v(-1.0, 0.5, 0.2);  // x = (0.004, 0.003, 0.3): 5 mm from the axis
  mlsBladeContactAt(c, rest, u, v, 2);
  const Vec3d x = rest + u, n(0.8, 0.6, 0.0);
  EXPECT_NEAR(segmentDistance(x, c.a0, c.b0), 0.01, 1e-15);
  EXPECT_NEAR(x.x, 0.008, 1e-15);
  EXPECT_NEAR(x.y, 0.006, 1e-15);
  EXPECT_NEAR(x.z, 0.3, 1e-15);
  EXPECT_NEAR(dot(v, n), 0.0, 1e-14);                     // into the blade: removed (it was -0.5)
  EXPECT_NEAR(v.x * 0.6 - v.y * 0.8, -1.0, 1e-14);        // tangential: kept
  EXPECT_NEAR(v.z, 0.2, 1e-14);
  Vec3d u_axis(-0.001, -0.002, 0.0), v_axis(0, 0, 0);     // exactly on the axis
  mlsBladeContactAt(c, rest, u_axis, v_axis, 1);
  EXPECT_NEAR(segmentDistance(rest + u_axis, c.a0, c.b0), 0.01, 1e-15);
  Vec3d u_out(0.02, 0.0, 0.0), v_out(-3.0, 1.0, 0.0);     // 21 mm away: untouched
  mlsBladeContactAt(c, rest, u_out, v_out, 3);
  EXPECT_EQ(u_out.x, 0.02);
  EXPECT_EQ(v_out.x, -3.0);
  Vec3d u_leaving(0.003, 0.001, 0.0), v_leaving(2.0, 0.0, 0.0);  // covered but moving out: keeps its velocity
  mlsBladeContactAt(c, rest, u_leaving, v_leaving, 2);
  EXPECT_EQ(v_leaving.x, 2.0);
  EXPECT_EQ(v_leaving.y, 0.0);
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
  for (const Vec3d& p : layers.nodal_points) d = std::min(d, segmentDistance(p, Vec3d(x, 0.002, -0.04), Vec3d(x, 0.002, 0.04)));
  return layers.nodal_points.empty() ? 1e9 : d;
}

TEST(CutBladeContact, NoNodalPointInsideTheBladeWhileItCuts) {
  const double r = 0.002;
  for (const double radius : {r, 0.0}) {
    auto sim = makeDissectionSimulation(cutBlock(radius), BackendKind::Cpu, Precision::Float64);
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
    auto sim = makeDissectionSimulation(s, BackendKind::Cpu, Precision::Float64);
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

}  // namespace
}  // namespace inc
