// DissectionSimulation with the MLS nodal points active while the blade is in the tissue: rest stays at rest, a
// pulled flap settles, mass through sphere -> points -> spheres, successive strokes, settings refused with their key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "host/sim/dissection_simulation.h"
#include "model/input_error.h"
#include "tests/support/cut_block_scene.h"

namespace inc {
namespace {

constexpr double kDt = 1.0 / 60.0;

ToolSpec scalpel(const std::string& name, std::vector<ToolKeyframe> path, double length = 0.08) {
  ToolSpec t;
  t.name = name;
  t.kind = "scalpel";
  t.length = length;
  t.path = std::move(path);
  return t;
}

// A 6 x 4 x 3 cm block of 1 cm metaballs without gravity. The scalpel (vertical 8 cm blade) enters at x = -5 cm
// in the plane y = 2 mm, reaches x = 0 at 0.15 s and stays in the tissue until `leave_s` (a partial cut held open).
Scene blockScene(double leave_s) {
  Scene s = cuttest::dissectionBlock("<test:coupled_block>");
  s.cutting.samples_per_diameter = 3;
  s.cutting.exchanges_per_frame = 2;
  s.tools = {scalpel("scalpel", {{0.05, Vec3d(-0.05, 0.002, 0.0), Vec3d(0, 0, 1)},
                                 {0.15, Vec3d(0.0, 0.002, 0.0), Vec3d(0, 0, 1)},
                                 {leave_s, Vec3d(0.0, 0.002, 0.0), Vec3d(0, 0, 1)}})};
  return s;
}

// No load, no gravity: the coupled system (PBD spheres, nodal points, springs, eq. 13) starts at rest and stays
// there to rounding while the points exist (max displacement < 1e-9 m, kinetic energy < 1e-15 J, float64), and
// after the re-packing.
TEST(CutCoupled, CoupledSystemAtRestStaysAtRest) {
  auto sim = makeDissectionSimulation(compileScene(blockScene(0.3)), BackendKind::Cpu, Precision::Float64);
  double points_max = 0;
  for (int f = 0; f < 22; ++f) {
    const FrameReport rep = sim->advance(kDt);
    ASSERT_TRUE(rep.finite) << f;
    points_max = std::max(points_max, rep.counters.at("nodal_points"));
    if (rep.counters.at("nodal_points") > 0) {
      EXPECT_GT(rep.counters.at("coupling_springs"), 0.0);
      EXPECT_GT(rep.counters.at("mls_substeps"), 0.0);
      EXPECT_EQ(rep.counters.at("coupling_exchanges"), 2.0);
    }
    EXPECT_LT(rep.max_displacement, 1e-9) << f;
    EXPECT_LT(rep.kinetic_energy, 1e-15) << f;
  }
  EXPECT_GT(points_max, 0.0);
  const FrameReport rep = sim->advance(kDt);
  EXPECT_EQ(rep.counters.at("cuts_applied"), 1.0);
  EXPECT_EQ(rep.counters.at("nodal_points"), 0.0);  // the points go back to zero between cuts
  EXPECT_LT(rep.max_displacement, 1e-9);
}

// Mass through sphere -> points -> spheres: the spheres still in PBD plus the points during the stroke, the
// spheres after it, equal the organ's mass to 1e-9 relative (float64; the issue asks 1e-6) in every frame.
TEST(CutCoupled, MassIsConservedThroughSpheresPointsAndSpheres) {
  Scene s = blockScene(0.2);
  s.solver.gravity = Vec3d(0, 0, -9.81);
  // The bottom layer (centres at z = -1 cm) held: a box that holds no sphere centre is refused since main's
  // 43c02b7 (the earlier z <= -1.2 mm box held none, and the block fell freely).
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(1, 1, -0.008)}};
  auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  const double m0 = sim->advance(kDt).counters.at("mass_kg");
  EXPECT_NEAR(m0, 0.06 * 0.04 * 0.03 * s.material.density_kg_m3, 1e-12);
  bool saw_points = false;
  for (int f = 0; f < 16; ++f) {
    const FrameReport rep = sim->advance(kDt);
    ASSERT_TRUE(rep.finite) << f;
    saw_points = saw_points || rep.counters.at("nodal_points") > 0;
    EXPECT_NEAR(rep.counters.at("mass_kg") / m0, 1.0, 1e-9) << f;
  }
  EXPECT_TRUE(saw_points);
  EXPECT_EQ(sim->advance(kDt).counters.at("cuts_applied"), 1.0);
}

// A flap: a horizontal blade cuts a 6 x 4 x 6 cm block (bottom layer held) halfway along x in the plane
// z = 0.3 mm and stays in the tissue; a grasper lifts the flap's free end by 1.5 cm and holds it. With the nodal
// points and the coupling active the flap settles: 0.6 s after the pull the rms velocity is below 2 mm/s (from
// ~4 cm/s while pulling; measured 0.9 mm/s), the largest displacement changes by less than 20 um per frame and
// the lifted end has moved by more than 5 mm (measured 15.2 mm for the 15 mm pull).
TEST(CutCoupled, PulledFlapReachesStaticEquilibrium) {
  Scene s;
  s.file = "<test:flap>";
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.size = Vec3d(0.06, 0.04, 0.06);
  s.geometry.spacing = 0.01;
  s.material.damping_per_s = 10.0;
  s.models.pbd_metaballs = true;
  s.models.cutting = true;
  s.solver.gravity = Vec3d(0, 0, 0);
  s.solver.substeps = 2;
  s.pbd.iterations = 5;
  s.cutting.samples_per_diameter = 3;
  s.cutting.exchanges_per_frame = 2;
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(1, 1, -0.02)}};
  s.tools = {scalpel("scalpel", {{0.02, Vec3d(-0.05, 0.0, 0.0003), Vec3d(0, 1, 0)},
                                 {0.1, Vec3d(0.0, 0.0, 0.0003), Vec3d(0, 1, 0)},
                                 {5.0, Vec3d(0.0, 0.0, 0.0003), Vec3d(0, 1, 0)}})};
  ToolSpec g;
  g.name = "grasper";
  g.kind = "grasper";
  g.radius = 0.003;
  g.path = {{0.12, Vec3d(-0.025, 0.0, 0.036), Vec3d(0, 0, -1)},  // just above the top face: no contact before
            {0.27, Vec3d(-0.025, 0.0, 0.051), Vec3d(0, 0, -1)},
            {5.0, Vec3d(-0.025, 0.0, 0.051), Vec3d(0, 0, -1)}};
  s.tools.push_back(g);
  auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  FrameReport rep;
  double mass = 0, v_pull = 0, disp_prev = 0, v_rms = 0;
  for (int f = 0; f < 54; ++f) {
    rep = sim->advance(kDt);
    ASSERT_TRUE(rep.finite) << f;
    mass = rep.counters.at("mass_kg");
    v_rms = std::sqrt(2.0 * rep.kinetic_energy / mass);
    if (f < 17) v_pull = std::max(v_pull, v_rms);
    if (f == 52) disp_prev = rep.max_displacement;
  }
  EXPECT_GT(rep.counters.at("nodal_points"), 0.0);  // the blade is still in: the points are simulated
  EXPECT_GT(rep.counters.at("grasped"), 0.0);
  EXPECT_GT(rep.max_displacement, 5e-3);
  EXPECT_GT(v_pull, 1e-2);
  EXPECT_LT(v_rms, 2e-3);
  EXPECT_LT(std::fabs(rep.max_displacement - disp_prev), 2e-5);  // m per frame
}

// Two scalpels are two strokes: the first separates the block along y = 2 mm, the points go back to zero, the
// second (along x = 1.3 mm) cuts both pieces: four sphere-graph components. Overlapping strokes are refused.
TEST(CutCoupled, SuccessiveStrokesInOneRun) {
  Scene s = blockScene(0.15);
  s.tools[0].path = {{0.05, Vec3d(-0.05, 0.002, 0.0), Vec3d(0, 0, 1)}, {0.15, Vec3d(0.05, 0.002, 0.0), Vec3d(0, 0, 1)}};
  s.tools.push_back(scalpel(
      "second", {{0.25, Vec3d(0.0013, -0.04, 0.0), Vec3d(0, 0, 1)}, {0.35, Vec3d(0.0013, 0.04, 0.0), Vec3d(0, 0, 1)}}));
  auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  FrameReport rep;
  double points_between = -1;
  for (int f = 0; f < 24; ++f) {
    rep = sim->advance(kDt);
    ASSERT_TRUE(rep.finite) << f;
    if (f == 12) {
      EXPECT_EQ(rep.counters.at("cuts_applied"), 1.0);
      EXPECT_EQ(rep.counters.at("sphere_components"), 2.0);
      points_between = rep.counters.at("nodal_points");
    }
  }
  EXPECT_EQ(points_between, 0.0);
  EXPECT_EQ(rep.counters.at("cuts_applied"), 2.0);
  EXPECT_EQ(rep.counters.at("sphere_components"), 4.0);
  EXPECT_EQ(rep.counters.at("nodal_points"), 0.0);
  s.tools[1].path[0].t = 0.1;  // starts before the first leaves the tissue
  try {
    makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
    FAIL() << "overlapping strokes accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tools"), std::string::npos) << e.what();
  }
}

// Bad synchronisation settings are refused naming their key, from a scene file and from code; a fixed MLS
// substep count above the nodal points' stable step too.
TEST(CutCoupled, BadCuttingSettingsAreInputErrorsNamingTheKey) {
  const std::string base = R"({"geometry": {"kind": "box", "size_m": [0.06, 0.04, 0.03], "spacing_m": 0.01},
    "models": {"pbd_metaballs": true, "cutting": true}, "cutting": {)";
  for (const char* bad :
       {R"("exchanges_per_frame": 0)", R"("samples_per_diameter": 1)", R"("pbd_substeps_per_exchange": 65)",
        R"("repack_spacing_factor": -1)", R"("repack_boundary_offset": 1.0)", R"("stroke_end_frames": 121)",
        R"("stroke_end_frames": -1)", R"("blade_radius_m": -0.001)", R"("conversion_delay_frames": 2)",
        R"("open_surface_frames": 121)", R"("blade_friction": -0.1)", R"("blade_friction": 2.5)",
        R"("conversion_delay_frames": -1)", R"("blade_radius_m": 0.2)", R"("unknown_key": 1)"}) {
    try {
      parseScene(base + bad + "}}", "<test>", ".");
      FAIL() << bad;
    } catch (const InputError& e) {
      const std::string key = std::string(bad).substr(1, std::string(bad).find('"', 1) - 1);
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
  const Scene good = parseScene(
      base + R"("exchanges_per_frame": 3, "repack_sphere_budget": 2, "stroke_end_frames": 4, "blade_radius_m": 0.001,
                                "conversion_delay_frames": 1, "open_surface_frames": 5, "blade_friction": 0.25})" +
          "}",
      "<test>", ".");
  EXPECT_EQ(good.cutting.exchanges_per_frame, 3);
  EXPECT_EQ(good.cutting.repack_sphere_budget, 2.0);
  EXPECT_EQ(good.cutting.stroke_end_frames, 4);
  EXPECT_EQ(parseScene(sceneToJson(good), "<test>", ".").cutting.exchanges_per_frame, 3);
  EXPECT_EQ(parseScene(sceneToJson(good), "<test>", ".").cutting.stroke_end_frames, 4);
  EXPECT_EQ(parseScene(sceneToJson(good), "<test>", ".").cutting.blade_radius_m, 0.001);
  EXPECT_EQ(parseScene(sceneToJson(good), "<test>", ".").cutting.conversion_delay_frames, 1);
  EXPECT_EQ(parseScene(sceneToJson(good), "<test>", ".").cutting.open_surface_frames, 5);
  EXPECT_EQ(parseScene(sceneToJson(good), "<test>", ".").cutting.blade_friction, 0.25);
  Scene s = blockScene(0.3);
  s.cutting.stroke_end_frames = 121;
  EXPECT_THROW(makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64), InputError);
  s = blockScene(0.3);
  s.cutting.conversion_delay_frames = 2;
  EXPECT_THROW(makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64), InputError);
  s = blockScene(0.3);
  s.cutting.open_surface_frames = -1;
  EXPECT_THROW(makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64), InputError);
  s = blockScene(0.3);
  s.cutting.blade_friction = std::nan("");
  EXPECT_THROW(makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64), InputError);
  s = blockScene(0.3);
  s.cutting.blade_radius_m = std::nan("");
  EXPECT_THROW(makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64), InputError);
  s = blockScene(0.3);
  s.cutting.exchanges_per_frame = 0;
  try {
    makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cutting.exchanges_per_frame"), std::string::npos) << e.what();
  }
  s = blockScene(0.3);
  s.cutting.mls_substeps_per_exchange = 1;  // 8 ms steps for points 5 mm apart: far above the stable step
  try {
    makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cutting.mls_substeps_per_exchange"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace inc
