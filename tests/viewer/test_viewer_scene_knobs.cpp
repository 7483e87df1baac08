// The Material / Solver knobs built from a scene: a Young's modulus change made through the runner (the UI's
// path) rebuilds the MLS beam and scales its measured deflection as linear elasticity says.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "host/scene/scene_loader.h"
#include "model/input_error.h"
#include "tests/support/repo_paths.h"
#include "viewer/scene_knobs.h"
#include "viewer/sim_runner.h"

namespace inc::viewer {
namespace {

// An 8 x 2 x 2 cm MLS cantilever (5 mm lattice, 256 particles) clamped at x < 5 mm, sagging under gravity,
// heavily damped so that it settles within 0.7 s of simulated time (slowest mode decays at 13.8 / s).
Scene smallBeam() {
  Scene s;
  s.file = "<test:knob_beam>";
  s.geometry.kind = GeometrySpec::Kind::Beam;
  s.geometry.center = Vec3d(0.04, 0, 0);
  s.geometry.size = Vec3d(0.08, 0.02, 0.02);
  s.geometry.spacing = 0.005;
  s.material.youngs_modulus_pa = 2.0e5;
  s.material.poisson_ratio = 0.3;
  s.material.damping_per_s = 150.0;
  s.solver.gravity = Vec3d(0, 0, -2.0);
  s.models.mls = true;
  s.solver.substeps = 0;
  s.solver.safety = 0.8;
  s.solver.backend = BackendKind::Cpu;
  s.solver.precision = Precision::Float64;
  s.fixed = {{Vec3d(-0.001, -0.011, -0.011), Vec3d(0.0051, 0.011, 0.011)}};
  return s;
}

std::size_t knobIndex(const std::vector<ViewerKnob>& knobs, const std::string& label) {
  for (std::size_t i = 0; i < knobs.size(); ++i)
    if (knobs[i].label == label) return i;
  return knobs.size();
}

// Mean z displacement from `rest` of the free end's particles (x > 7.5 cm) after `frames` more frames.
double tipDeflection(SimRunner& run, const std::vector<Vec3d>& rest, int frames) {
  SimSnapshot s;
  std::uint64_t ver = 0;
  for (int i = 0; i < frames; ++i) run.pump();
  run.latest(s, ver);
  EXPECT_FALSE(s.failed) << s.failure;
  double dz = 0;
  int n = 0;
  for (std::size_t i = 0; i < rest.size(); ++i)
    if (rest[i].x > 0.075) {
      dz += s.positions[i].z - rest[i].z;
      ++n;
    }
  return n ? dz / n : 0.0;
}

TEST(ViewerSceneKnobs, PanelsComeFromTheScene) {
  const SceneViewerSetup setup = makeSceneViewerSetup(smallBeam());
  const auto& k = setup.knobs;
  for (const char* label :
       {"Young's modulus [Pa]", "Poisson ratio", "substeps (0 = auto)", "time step [s]", "precision", "backend"})
    EXPECT_LT(knobIndex(k, label), k.size()) << label;
  EXPECT_EQ(knobIndex(k, "PBD iterations"), k.size());  // an MLS scene has no PBD iterations
  EXPECT_DOUBLE_EQ(k[knobIndex(k, "Young's modulus [Pa]")].value, 2.0e5);
  EXPECT_DOUBLE_EQ(k[knobIndex(k, "Poisson ratio")].value, 0.3);
  EXPECT_DOUBLE_EQ(k[knobIndex(k, "precision")].value, 1.0);  // float64
  EXPECT_EQ(k[knobIndex(k, "Young's modulus [Pa]")].group, "Material");
  EXPECT_EQ(k[knobIndex(k, "backend")].group, "Solver");
}

// A PBD scene has the solver knobs; the Chebyshev estimate with Gauss-Seidel is refused by the model factory
// (InputError naming pbd.chebyshev_rho), so the viewer's rebuild is undone; with Jacobi it builds.
TEST(ViewerSceneKnobs, PbdSolverKnobsAndTheChebyshevRule) {
  Scene s = smallBeam();
  s.models.mls = false;
  s.models.pbd_metaballs = true;
  s.solver.substeps = 4;
  s.solver.precision = Precision::Float32;
  const SceneViewerSetup setup = makeSceneViewerSetup(s);
  const auto& k = setup.knobs;
  const std::size_t solver = knobIndex(k, "PBD solver"), rho = knobIndex(k, "PBD Chebyshev rho (Jacobi)");
  ASSERT_LT(solver, k.size());
  ASSERT_LT(rho, k.size());
  EXPECT_DOUBLE_EQ(k[rho].max_value, 0.9);
  k[rho].edit(0.9);
  EXPECT_NO_THROW(setup.factory());
  k[solver].edit(1.0);  // gauss_seidel
  EXPECT_EQ(setup.scene->pbd.solver, "gauss_seidel");
  try {
    setup.factory();
    ADD_FAILURE() << "Chebyshev with Gauss-Seidel built";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "pbd.chebyshev_rho");
  }
}

// A cutting scene has the Cutting knobs (stroke end delay, conversion delay, surface opening, blade contact radius)
// at the scene's values; an edit
// reaches the scene copy the factory builds from, and the rebuilt model takes it (the edited delay shows as frames
// with a stroke end pending). Only cutting scenes have them.
TEST(ViewerSceneKnobs, CuttingKnobsReachTheModel) {
  Scene s = loadSceneFile(test::sourcePath("scenes/steak_cut.json"));
  s.solver.backend = BackendKind::Cpu;
  const SceneViewerSetup setup = makeSceneViewerSetup(s);
  const auto& k = setup.knobs;
  const std::size_t delay = knobIndex(k, "stroke end delay [frames]"), blade = knobIndex(k, "blade contact radius [m]");
  ASSERT_LT(delay, k.size());
  ASSERT_LT(blade, k.size());
  EXPECT_EQ(k[delay].group, "Cutting");
  EXPECT_DOUBLE_EQ(k[delay].value, 3.0);
  EXPECT_DOUBLE_EQ(k[blade].value, 0.0);
  const std::size_t conversion = knobIndex(k, "conversion delay [frames]");
  ASSERT_LT(conversion, k.size());
  EXPECT_DOUBLE_EQ(k[conversion].value, 0.0);
  const std::size_t open = knobIndex(k, "open surface every [frames]");
  ASSERT_LT(open, k.size());
  EXPECT_DOUBLE_EQ(k[open].value, 0.0);
  k[open].edit(2.0);
  EXPECT_EQ(setup.scene->cutting.open_surface_frames, 2);
  const std::size_t friction = knobIndex(k, "blade friction");
  ASSERT_LT(friction, k.size());
  k[friction].edit(0.3);
  EXPECT_DOUBLE_EQ(setup.scene->cutting.blade_friction, 0.3);
  k[delay].edit(5.0);
  k[blade].edit(0.001);
  k[conversion].edit(1.0);
  EXPECT_EQ(setup.scene->cutting.conversion_delay_frames, 1);
  EXPECT_EQ(setup.scene->cutting.stroke_end_frames, 5);
  EXPECT_DOUBLE_EQ(setup.scene->cutting.blade_radius_m, 0.001);
  auto model = setup.factory();
  int pending = 0, applied_at = -1;
  for (int f = 0; f < 40 && applied_at < 0; ++f) {
    const FrameReport rep = model->advance(s.solver.frame_dt);
    ASSERT_TRUE(rep.finite) << f;
    pending += rep.counters.at("stroke_end_pending") > 0 ? 1 : 0;
    if (rep.counters.at("cuts_applied") > 0) applied_at = f;
  }
  EXPECT_GT(applied_at, 0);
  EXPECT_EQ(pending, 5);
  EXPECT_EQ(knobIndex(makeSceneViewerSetup(smallBeam()).knobs, "stroke end delay [frames]"),
            makeSceneViewerSetup(smallBeam()).knobs.size());
}

// Doubling E through the UI's path halves the small-deflection tip sag (Euler-Bernoulli: delta = q L^4 / 8 E I,
// proportional to 1 / E). Tolerance 2 % (measured 0.08 %): gravity is reduced to 2 m/s^2 so that the sag is 2 % of the
// length at E = 2e5 Pa (geometric nonlinearity well under the tolerance); both runs settle (damping 150 / s, 0.67 s:
// the slowest mode to e^-9).
TEST(ViewerSceneKnobs, YoungsModulusChangeRebuildsAndScalesTheDeflection) {
  SceneViewerSetup setup = makeSceneViewerSetup(smallBeam());
  SimRunner run(nullptr, setup.factory, setup.knobs, 1.0 / 60.0, /*threaded=*/false);
  const std::size_t ei = knobIndex(run.knobs(), "Young's modulus [Pa]");
  ASSERT_LT(ei, run.knobs().size());
  SimSnapshot s;
  std::uint64_t ver = 0;
  run.latest(s, ver);
  const std::vector<Vec3d> rest = s.positions;  // frame 0: the rest configuration (a rebuild starts there too)
  const double d1 = tipDeflection(run, rest, 40);
  ASSERT_LT(d1, -1e-4);  // it sags
  run.setKnob(ei, 4.0e5);
  run.pump();  // applies the edit (a rebuild from the edited scene) and advances one frame
  run.latest(s, ver);
  EXPECT_EQ(s.rebuilds, 1u);
  EXPECT_EQ(s.frame, 1u);
  EXPECT_DOUBLE_EQ(setup.scene->material.youngs_modulus_pa, 4.0e5);
  const double d2 = tipDeflection(run, rest, 39);
  std::printf("tip sag %.6g m at E = 2e5 Pa, %.6g m at 4e5 Pa, ratio %.4f\n", d1, d2, d2 / d1);
  EXPECT_NEAR(d2 / d1, 0.5, 0.01) << "d1 " << d1 << " d2 " << d2;
}

// A rebuild that fails (an unstable fixed substep count) keeps the running model, undoes the scene edit and
// says why; the time step knob changes the runner's frame time without a rebuild.
TEST(ViewerSceneKnobs, FailedRebuildIsUndoneAndTimeStepIsLive) {
  SceneViewerSetup setup = makeSceneViewerSetup(smallBeam());
  SimRunner run(nullptr, setup.factory, setup.knobs, 1.0 / 60.0, false);
  const auto knobs = run.knobs();
  run.setKnob(knobIndex(knobs, "substeps (0 = auto)"), 1);  // 1 substep of 16 ms: far above the stable step
  run.pump();
  SimSnapshot s;
  std::uint64_t ver = 0;
  run.latest(s, ver);
  EXPECT_EQ(s.rebuilds, 0u);
  EXPECT_NE(s.message.find("not rebuilt"), std::string::npos) << s.message;
  EXPECT_EQ(setup.scene->solver.substeps, 0);
  EXPECT_DOUBLE_EQ(run.knobs()[knobIndex(knobs, "substeps (0 = auto)")].value, 0.0);
  run.setKnob(knobIndex(knobs, "time step [s]"), 0.005);
  run.pump();
  EXPECT_DOUBLE_EQ(run.frameDt(), 0.005);
  run.latest(s, ver);
  EXPECT_EQ(s.rebuilds, 0u);
  EXPECT_NEAR(s.report.dt * s.report.substeps, 0.005, 1e-12);
  // 64 fixed substeps are stable for 5 ms frames but not for 50 ms ones: the model refuses the longer frame
  // (InputError from advance), the runner keeps the state, pauses and says so.
  run.setKnob(knobIndex(knobs, "substeps (0 = auto)"), 64);
  run.pump();
  run.latest(s, ver);
  ASSERT_EQ(s.rebuilds, 1u) << s.message;
  run.setKnob(knobIndex(knobs, "time step [s]"), 0.05);
  run.pump();
  run.latest(s, ver);
  EXPECT_TRUE(run.paused());
  EXPECT_NE(s.message.find("frame refused"), std::string::npos) << s.message;
}

// The UI's tool path: events queued on the runner reach the model before the next frame. A grasp on the free
// end of the beam, dragged 10 mm up, holds the grasped nodes there (MLS: prescribed, exact to 1e-9 m) and the
// snapshot reports what is held; a cut event on a model that cannot cut is reported, not applied.
TEST(ViewerRunnerTool, QueuedGraspReachesTheModel) {
  SceneViewerSetup setup = makeSceneViewerSetup(smallBeam());
  SimRunner run(nullptr, setup.factory, {}, 1.0 / 60.0, false);
  SimSnapshot s;
  std::uint64_t ver = 0;
  run.latest(s, ver);
  EXPECT_TRUE(s.tool_support.grasp);
  EXPECT_FALSE(s.tool_support.cut);
  const std::vector<Vec3d> rest = s.positions;
  ToolEvent e;
  e.kind = ToolKind::Grasp;
  e.phase = ToolPhase::Press;
  e.tip = Vec3d(0.08, 0.0, 0.0);
  e.radius_m = 0.006;
  run.queueTool(e);
  e.phase = ToolPhase::Drag;
  e.tip = Vec3d(0.08, 0.0, 0.01);
  run.queueTool(e);
  for (int i = 0; i < 3; ++i) run.pump();
  run.latest(s, ver);
  ASSERT_GT(s.last_tool.grasped, 0);
  int held = 0;
  for (std::size_t i = 0; i < rest.size(); ++i)
    if (norm(rest[i] - Vec3d(0.08, 0.0, 0.0)) <= 0.006) {
      EXPECT_NEAR(s.positions[i].z - rest[i].z, 0.01, 1e-9);
      ++held;
    }
  EXPECT_EQ(held, s.last_tool.grasped);
  e.kind = ToolKind::Cut;
  e.phase = ToolPhase::Press;
  run.queueTool(e);
  run.pump();
  run.latest(s, ver);
  EXPECT_FALSE(s.last_tool.supported);
  EXPECT_NE(s.message.find("does not support"), std::string::npos) << s.message;
}

}  // namespace
}  // namespace inc::viewer
