// Coulomb friction of moving tool capsules on PBD spheres (`tools[k].friction`, `cutting.blade_friction`): the
// impulse limit on one sphere against its analytic value, an organ dragged by a probe, and the scene keys.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cpu_fallback/pbd_solver_cpu.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "host/sim/metaball_simulation.h"
#include "model/input_error.h"
#include "model/pbd_model.h"
#include "physics/pbd_block.h"
#include "tests/support/pbd_fixtures.h"

namespace inc {
namespace {

constexpr double kDt = 1.0 / 60.0;

// A free sphere (1 cm, no gravity, no constraints) hit by a long capsule moving down onto it at vn and along its own
// axis at vt, for 0.5 s: the sphere's final velocity. Frictionless, a tool sliding along its axis exerts no
// tangential force. With friction the normal impulse that brings the sphere to vn bounds the tangential one by mu
// vn, so it leaves sliding at mu vn, or sticking at vt where mu vn >= vt. Position-based: the pushes of the two
// substeps that bring it to vn add up to vn dt exactly, and each allows mu times itself of relative tangential
// displacement, so the figures hold to rounding.
Vec3d velocityAfterImpact(double mu, double vn, double vt, PbdSolverKind solver) {
  auto b = cpu::makePbdCpuBackend<double>();
  b->setModel(test::makeFreeSphere());
  PbdStepParams<double> p;
  p.solver = solver;
  p.substeps = 4;
  p.iterations = 5;
  p.damping = 0.0;
  p.gravity = Vec3d();
  p.volume_preservation = false;
  const auto tool = [&](double t) {
    pbd::CapsuleCollider<double> c;
    const double z = 0.0151 - vn * t, x = vt * t;  // 0.1 mm above the sphere at t = 0
    c.a = Vec3d(x - 0.5, 0, z);
    c.b = Vec3d(x + 0.5, 0, z);
    c.radius = 0.005;
    c.friction = mu;
    return c;
  };
  for (int f = 0; f < 30; ++f) {
    PbdFrameInput<double> in;
    in.tools_from.push_back(tool(f * kDt));
    in.tools_to.push_back(tool((f + 1) * kDt));
    b->advanceFrame(p, in);
  }
  PbdState<double> st;
  b->getState(st);
  return st.velocities[0];
}

TEST(ToolFriction, AnImpactGivesTheTangentialSpeedCoulombAllows) {
  const double vn = 0.1, vt = 0.2;
  for (const PbdSolverKind solver : {PbdSolverKind::GaussSeidel, PbdSolverKind::Jacobi})
    for (const double mu : {0.0, 0.5, 1.0, 1.5, 2.0}) {
      const Vec3d v = velocityAfterImpact(mu, vn, vt, solver);
      EXPECT_NEAR(v.z, -vn, 1e-12) << "pushed down with the tool, mu " << mu;
      EXPECT_NEAR(v.x, std::min(vt, mu * vn), 1e-12) << "mu " << mu << (mu * vn >= vt ? " (sticks)" : " (slides)");
      EXPECT_NEAR(v.y, 0.0, 1e-15);
    }
}

// A tool at rest holds a sphere like a static collider: pressed between the tool (mu 1) and a frictionless floor
// under gravity tilted 20 degrees off the vertical, the sphere stays; frictionless it slides with the tilt.
TEST(ToolFriction, AToolAtRestHoldsASphereAgainstASlidingForce) {
  const auto drift = [](double mu) {
    auto b = cpu::makePbdCpuBackend<double>();
    b->setModel(test::makeFreeSphere({{Vec3d(0, 0, 1), -0.01, 0.0}}));  // the sphere rests on the floor
    PbdStepParams<double> p;
    p.solver = PbdSolverKind::GaussSeidel;
    p.substeps = 4;
    p.iterations = 5;
    p.damping = 0.0;
    const double a = M_PI / 9;
    p.gravity = Vec3d(9.81 * std::sin(a), 0, -9.81 * std::cos(a));
    pbd::CapsuleCollider<double> c;  // a tool along y pressing 1 mm into the sphere's top
    c.a = Vec3d(0, -0.5, 0.014);
    c.b = Vec3d(0, 0.5, 0.014);
    c.radius = 0.005;
    c.friction = mu;
    PbdFrameInput<double> in;
    in.tools_from = in.tools_to = {c};
    for (int f = 0; f < 60; ++f) b->advanceFrame(p, in);
    PbdState<double> st;
    b->getState(st);
    return st.positions[0].x;
  };
  const double free = drift(0.0), held = drift(1.0);
  std::printf("[tool friction] pressed sphere on a tilted floor after 1 s: mu 0 %.4f m, mu 1 %.2e m\n", free, held);
  EXPECT_GT(free, 0.05) << "frictionless: it slides out from under the tool";
  EXPECT_LT(std::fabs(held), 1e-3) << "the tool's friction holds it";
}

// A probe along x pressing 2 mm into the top of a 4 x 4 x 2 cm metaball block that rests on a frictionless floor,
// then sliding along its own axis at 5 cm/s for 1 s. Frictionless, nothing pushes the block along x (its contact
// normals are perpendicular to the probe's axis): it stays put to rounding. With mu 1 the pressed top is dragged,
// and the block, free on the floor, is carried along: its mean x velocity reaches the probe's within 5 %.
struct Dragged {
  double mean_dx = 0, mean_vx = 0;
};
Dragged dragBlock(double mu) {
  const std::string json =
      R"({"name": "drag", "geometry": {"kind": "box", "size_m": [0.04, 0.04, 0.02], "spacing_m": 0.01},
    "models": {"pbd_metaballs": true},
    "colliders": [{"kind": "plane", "point_m": [0, 0, -0.01], "normal": [0, 0, 1]}],
    "tools": [{"name": "probe", "kind": "probe", "radius_m": 0.005, "length_m": 0.2, "friction": )" +
      std::to_string(mu) + R"(,
               "path": [{"t_s": 0, "position_m": [0.1, 0, 0.0155], "direction": [1, 0, 0]},
                        {"t_s": 0.25, "position_m": [0.1, 0, 0.0155], "direction": [1, 0, 0]},
                        {"t_s": 1.25, "position_m": [0.15, 0, 0.0155], "direction": [1, 0, 0]}]}]})";
  const Scene s = parseScene(json, "drag.json", ".");
  auto m = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  std::vector<Vec3d> x0, x1, x2;
  m->currentPositions(x0);
  for (int f = 0; f < 74; ++f) EXPECT_TRUE(m->advance(kDt).finite);
  m->currentPositions(x1);
  EXPECT_TRUE(m->advance(kDt).finite);
  m->currentPositions(x2);
  Dragged d;
  for (std::size_t i = 0; i < x0.size(); ++i) {
    d.mean_dx += (x2[i].x - x0[i].x) / double(x0.size());
    d.mean_vx += (x2[i].x - x1[i].x) / kDt / double(x0.size());
  }
  return d;
}

TEST(ToolFriction, AProbeDragsTheOrganItPresses) {
  const Dragged free = dragBlock(0.0), held = dragBlock(1.0);
  std::printf("[tool friction] probe at 0.05 m/s: mu 0 moved %.2e m, mu 1 moved %.4f m at %.4f m/s\n", free.mean_dx,
              held.mean_dx, held.mean_vx);
  EXPECT_LT(std::fabs(free.mean_dx), 1e-9);
  EXPECT_NEAR(held.mean_vx / 0.05, 1.0, 0.05);
  EXPECT_NEAR(held.mean_dx / 0.05, 1.0, 0.05) << "carried from the start: 1 s at 5 cm/s";
}

std::string toolError(const std::string& tool) {
  try {
    parseScene(R"({"name": "t", "geometry": {"kind": "box", "size_m": [0.04, 0.04, 0.02], "spacing_m": 0.01},
                   "models": {"pbd_metaballs": true}, "tools": [)" +
                   tool + "]}",
               "t.json", ".");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ToolFriction, TheSceneKeyParsesRoundTripsAndRefusesBadValues) {
  const std::string path = R"("path": [{"t_s": 0, "position_m": [0, 0, 0.05]}])";
  const Scene s =
      parseScene(R"({"name": "t", "geometry": {"kind": "box", "size_m": [0.04, 0.04, 0.02], "spacing_m": 0.01},
      "models": {"pbd_metaballs": true}, "tools": [{"kind": "probe", "friction": 0.7, )" +
                     path + "}]}",
                 "t.json", ".");
  ASSERT_EQ(s.tools.size(), 1u);
  EXPECT_DOUBLE_EQ(s.tools[0].friction, 0.7);
  EXPECT_DOUBLE_EQ(parseScene(sceneToJson(s), "again.json", ".").tools[0].friction, 0.7);
  EXPECT_NE(toolError(R"({"kind": "probe", "friction": -0.1, )" + path + "}").find("tools[0].friction"),
            std::string::npos);
  EXPECT_NE(toolError(R"({"kind": "grasper", "friction": 2.5, )" + path + "}").find("[0, 2]"), std::string::npos);
  EXPECT_NE(toolError(R"({"kind": "scalpel", "friction": 0.5, )" + path + "}").find("cutting.blade_friction"),
            std::string::npos);
  EXPECT_EQ(toolError(R"({"kind": "grasper", "friction": 2, )" + path + "}"), "");
}

// The frame input is checked: a tool's friction outside [0, 2] (or NaN) is refused before any frame runs.
TEST(ToolFriction, AFrameInputWithBadToolFrictionIsRefused) {
  auto b = cpu::makePbdCpuBackend<double>();
  b->setModel(test::makeFreeSphere());
  pbd::CapsuleCollider<double> c;
  c.b = Vec3d(1, 0, 0);
  c.radius = 0.001;
  for (const double mu : {-0.5, 3.0, std::nan("")}) {
    c.friction = mu;
    PbdFrameInput<double> in;
    in.tools_from = in.tools_to = {c};
    EXPECT_THROW(b->advanceFrame(PbdStepParams<double>{}, in), InputError) << "mu " << mu;
  }
}

}  // namespace
}  // namespace inc
