// A stroke's end applied cutting.stroke_end_frames frames after the blade leaves: the same cut as an immediate end,
// the points simulated meanwhile, deterministic, a retried frame counted once, a new stroke applying it at once.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "host/assembly/organ_shapes.h"
#include "host/cut/cut_stroke_end.h"
#include "host/io/mesh.h"
#include "host/scene/scene_compile.h"
#include "host/sim/dissection_simulation.h"
#include "model/input_error.h"
#include "tests/support/cut_block_scene.h"
#include "tests/support/cut_fixtures.h"
#include "tests/support/cut_surface_fixtures.h"
#include "tests/support/held_idle_workers.h"

namespace inc {
namespace {

constexpr double kDt = 1.0 / 60.0;

// The fixture's block cut through by 0.15 s (the blade leaves in frame 8), falling freely (or at rest without gravity).
Scene fallingBlock(int stroke_end_frames, bool gravity = true) {
  Scene s = cuttest::cutBlockScene(0.15, gravity, "<test:stroke_end>");
  s.cutting.stroke_end_frames = stroke_end_frames;
  return s;
}

struct Recording {
  std::vector<FrameReport> frames;
  std::vector<std::vector<Vec3d>> surfaces;  // the skinned surface after each frame
  std::vector<Vec3d> positions;              // the spheres after the last frame
  TriangleMesh last_surface;
};

Recording record(const Scene& s, int frames) {
  Recording r;
  auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  for (int f = 0; f < frames; ++f) {
    r.frames.push_back(sim->advance(kDt));
    EXPECT_TRUE(r.frames.back().finite) << f;
    EXPECT_TRUE(sim->currentSurface(r.last_surface));
    r.surfaces.push_back(r.last_surface.vertices);
  }
  sim->currentPositions(r.positions);
  return r;
}

// Bit for bit (no tolerance): the same operations in the same order.
bool same(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].x != b[i].x || a[i].y != b[i].y || a[i].z != b[i].z) return false;
  return true;
}

int firstApplied(const Recording& r) {
  for (std::size_t f = 0; f < r.frames.size(); ++f)
    if (r.frames[f].counters.at("cuts_applied") > 0) return int(f);
  return -1;
}

// The cut applied 3 frames late is the same cut: the same spheres, links, components, surface triangles and
// re-packing figures as applied at once (all of it is rest-configuration work); the points are simulated in the
// 3 frames between (mass to 1e-9 relative in every frame), and the state carries over: the applying frame changes
// no surface vertex's velocity by more than 2.5 x the largest change of a frame just before (the re-bound skin
// alone gives 1.4 x; new spheres that lost their points' displacement and velocity give 26 x).
TEST(CutStrokeEnd, DeferredEndIsTheSameCutWithThePointsSimulatedMeanwhile) {
  const int delay = 3, frames = 18;
  const Recording now = record(fallingBlock(0), frames);
  const Recording late = record(fallingBlock(delay), frames);
  const int fe = firstApplied(now);
  ASSERT_GT(fe, 0);
  ASSERT_EQ(firstApplied(late), fe + delay);
  const double m0 = now.frames[0].counters.at("mass_kg");
  for (int f = 0; f < frames; ++f) {
    const auto& c = late.frames[std::size_t(f)].counters;
    EXPECT_NEAR(c.at("mass_kg") / m0, 1.0, 1e-9) << f;
    const bool waiting = f >= fe && f < fe + delay;
    EXPECT_EQ(c.at("stroke_end_pending"), waiting ? 1.0 : 0.0) << f;
    if (waiting) {
      EXPECT_GT(c.at("nodal_points"), 0.0) << f;
    }
    if (f < fe) {
      EXPECT_TRUE(same(late.surfaces[std::size_t(f)], now.surfaces[std::size_t(f)])) << f;  // bit for bit
    }
  }
  const auto& a = now.frames[std::size_t(fe)].counters;
  const auto& b = late.frames[std::size_t(fe + delay)].counters;
  for (const char* key : {"spheres", "links", "sphere_components", "surface_components", "surface_split",
                          "spheres_added_last_cut", "nodal_points_last_cut", "repack_packed", "repack_merged"})
    EXPECT_EQ(a.at(key), b.at(key)) << key;
  EXPECT_EQ(b.at("sphere_components"), 2.0);
  EXPECT_EQ(b.at("surface_components"), 2.0);
  EXPECT_EQ(b.at("nodal_points"), 0.0);
  EXPECT_EQ(now.last_surface.triangles, late.last_surface.triangles);
  // The applying frame moves the surface no more than the frames before it did.
  const std::size_t before = late.surfaces[std::size_t(fe + delay - 1)].size();  // vertices keep their index
  const auto kick =
      [&](int f) {  // largest |x(f) - 2 x(f-1) + x(f-2)| over the vertices: the frame's change of velocity
        double m = 0;
        for (std::size_t v = 0; v < before; ++v)
          m = std::max(m, norm(late.surfaces[std::size_t(f)][v] - late.surfaces[std::size_t(f - 1)][v] * 2.0 +
                               late.surfaces[std::size_t(f - 2)][v]));
        return m;
      };
  double typical = 0;
  for (int f = fe + 2; f < fe + delay; ++f) typical = std::max(typical, kick(f));
  const double jump = kick(fe + delay);
  EXPECT_GT(typical, 1e-5);  // the block falls while the end is in the making
  EXPECT_LT(jump, 2.5 * typical) << "typical " << typical;
  // Deterministic: the worker's timing changes nothing.
  const Recording again = record(fallingBlock(delay), frames);
  EXPECT_TRUE(same(again.positions, late.positions));
}

// No load: the organ stays at rest through the delay and the applied end (1e-9 m, 1e-15 J; float64).
TEST(CutStrokeEnd, RestStaysAtRestThroughTheDelay) {
  const Recording r = record(fallingBlock(4, false), 16);
  ASSERT_GT(firstApplied(r), 0);
  for (std::size_t f = 0; f < r.frames.size(); ++f) {
    EXPECT_LT(r.frames[f].max_displacement, 1e-9) << f;
    EXPECT_LT(r.frames[f].kinetic_energy, 1e-15) << f;
  }
}

// The numerical guard's retry of a frame inside the delay (restore the checkpoint, advance again) counts that
// frame once: the cut is applied in the same frame and the run ends bit for bit where an undisturbed one does.
TEST(CutStrokeEnd, RetriedFrameInsideTheDelayCountsOnce) {
  const int delay = 3, frames = 16;
  const Recording plain = record(fallingBlock(delay), frames);
  const int fe = firstApplied(plain) - delay;
  auto sim = makeDissectionSimulation(compileScene(fallingBlock(delay)), BackendKind::Cpu, Precision::Float64);
  int applied_at = -1;
  for (int f = 0; f < frames; ++f) {
    if (f == fe + 1) {
      sim->saveCheckpoint();
      ASSERT_TRUE(sim->advance(kDt).finite);
      sim->restoreCheckpoint();
    }
    const FrameReport rep = sim->advance(kDt);
    ASSERT_TRUE(rep.finite) << f;
    if (applied_at < 0 && rep.counters.at("cuts_applied") > 0) applied_at = f;
  }
  EXPECT_EQ(applied_at, fe + delay);
  std::vector<Vec3d> x;
  sim->currentPositions(x);
  EXPECT_TRUE(same(x, plain.positions));
}

// A worker starved past the end's due frame (held, as a busy machine without the right to raise its priority
// starves it, and its OpenMP threads even when boosted: seconds measured under a CI run) is not waited for
// longer than patience(): the due frame computes the end itself, the same cut, bit for bit.
TEST(CutStrokeEnd, StarvedWorkerIsReplacedByTheDueFrame) {
  const int delay = 3, frames = 16;
  const Recording plain = record(fallingBlock(delay), frames);
  const int applied = firstApplied(plain);
  ASSERT_GT(applied, 0);
  auto sim = makeDissectionSimulation(compileScene(fallingBlock(delay)), BackendKind::Cpu, Precision::Float64);
  cuttest::HeldIdleWorkers held;
  TriangleMesh surface;
  for (int f = 0; f < frames; ++f) {
    const FrameReport rep = sim->advance(kDt);
    ASSERT_TRUE(rep.finite) << f;
    EXPECT_EQ(rep.counters.at("cuts_applied"), f >= applied ? 1.0 : 0.0) << f;
    if (f == applied) {
      EXPECT_EQ(rep.counters.at("stroke_end_here"), 1.0);
    }
    ASSERT_TRUE(sim->currentSurface(surface));
    EXPECT_TRUE(same(surface.vertices, plain.surfaces[std::size_t(f)])) << f;
  }
  EXPECT_EQ(held.held(), 1);  // the worker did start, and waited at the gate throughout
  std::vector<Vec3d> x;
  sim->currentPositions(x);
  EXPECT_TRUE(same(x, plain.positions));
}

// A stroke that begins while another's end is in the making applies that end first (at once, not after the
// delay), then cuts the new pieces: a mouse stroke across the block right after the scripted one.
TEST(CutStrokeEnd, NewStrokeAppliesThePendingEndFirst) {
  const int delay = 5;
  auto sim = makeDissectionSimulation(compileScene(fallingBlock(delay, false)), BackendKind::Cpu, Precision::Float64);
  int f = 0;
  for (; f < 30; ++f) {
    const FrameReport rep = sim->advance(kDt);
    ASSERT_TRUE(rep.finite);
    if (rep.counters.at("stroke_end_pending") > 0) break;
  }
  ASSERT_LT(f, 30);
  ToolEvent e = cuttest::mouseScalpel();
  e.phase = ToolPhase::Press;
  e.tip = Vec3d(0.012, -0.05, 0.0);
  ASSERT_TRUE(sim->applyTool(e).supported);
  FrameReport rep = sim->advance(kDt);
  EXPECT_EQ(rep.counters.at("cuts_applied"), 1.0);  // the scripted stroke's end, applied by the Press
  EXPECT_EQ(rep.counters.at("stroke_end_pending"), 0.0);
  EXPECT_EQ(rep.counters.at("sphere_components"), 2.0);
  e.phase = ToolPhase::Release;
  e.tip = Vec3d(0.012, 0.05, 0.0);
  EXPECT_TRUE(sim->applyTool(e).cut_applied);
  for (int k = 0; k < delay; ++k) {
    rep = sim->advance(kDt);
    EXPECT_EQ(rep.counters.at("cuts_applied"), k + 1 < delay ? 1.0 : 2.0) << k;
  }
  EXPECT_GE(rep.counters.at("sphere_components"), 3.0);
  EXPECT_EQ(rep.counters.at("stroke_end_pending"), 0.0);
}

// A mouse blade path that turns back over its own sweep: the surface split cannot make a consistent surface of it
// (CutSplitFailed). The cut is applied to spheres and points, the surface is left unsplit for it (the new counter
// surface_split_failed) and the run goes on.
TEST(CutStrokeEnd, InteractiveStrokeTurningBackLeavesTheSurfaceUnsplit) {
  const std::vector<double> xs = {-0.05, -0.01, 0.03, -0.02, 0.02};
  Scene s = cuttest::mouseCutBlockScene(false, "<test:stroke_end>");
  s.cutting.stroke_end_frames = 2;
  auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  ToolEvent e = cuttest::mouseScalpel();
  for (std::size_t k = 0; k < xs.size(); ++k) {
    e.phase = k == 0 ? ToolPhase::Press : k + 1 == xs.size() ? ToolPhase::Release : ToolPhase::Drag;
    e.tip = Vec3d(xs[k], 0.002, 0.0);
    ASSERT_NO_THROW(sim->applyTool(e)) << k;
    ASSERT_TRUE(sim->advance(kDt).finite) << k;
  }
  FrameReport rep;
  for (int f = 0; f < 3; ++f) ASSERT_NO_THROW(rep = sim->advance(kDt));
  EXPECT_EQ(rep.counters.at("cuts_applied"), 1.0);
  EXPECT_EQ(rep.counters.at("surface_split_failed"), 1.0);
  EXPECT_EQ(rep.counters.at("surface_split"), 0.0);
  EXPECT_GT(rep.counters.at("nodal_points_last_cut"), 0.0);
  EXPECT_EQ(rep.counters.at("nodal_points"), 0.0);
  for (int f = 0; f < 10; ++f) ASSERT_TRUE(sim->advance(kDt).finite) << f;  // the run goes on
}

// computeStrokeEnd alone, with a sweep the surface split refuses as input (a triangle not of the strip pattern):
// a scripted stroke's end rethrows it (naming the swept surface); an interactive one leaves the surface as it was,
// says why, and still binds the skin to the spheres.
TEST(CutStrokeEnd, RefusedSweepFailsAScriptedEndAndLeavesAnInteractiveOneUnsplit) {
  const CutSurfaceState before = cutSurfaceState(makeBoxMesh(Vec3d(0.02, 0.02, 0.02), 4));
  StrokeEndInput in;
  in.kept = cuttest::latticeBlock(4, 4, 4);
  in.cuts = {cuttest::straightBladeSweep(Vec3d(-0.03, 0.001, -0.05), Vec3d(-0.03, 0.001, 0.05), Vec3d(0.06, 0, 0))};
  std::swap(in.cuts[0].triangles[0][1], in.cuts[0].triangles[0][2]);  // not the strip pattern of sweepSurface
  in.surface = std::make_shared<const CutSurfaceState>(before);
  BackgroundTask beside;
  in.interactive = false;
  try {
    computeStrokeEnd(in, beside, [](const MetaballModel&) {});
    FAIL() << "the refused sweep was split";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("swept surface"), std::string::npos) << e.what();
  }
  in.interactive = true;
  const StrokeEndResult r = computeStrokeEnd(in, beside, [](const MetaballModel&) {});
  EXPECT_FALSE(r.split);
  EXPECT_NE(r.split_failure.find("strip"), std::string::npos) << r.split_failure;
  EXPECT_EQ(r.surface.mesh.triangles, before.mesh.triangles);
  EXPECT_EQ(r.skin.rest_vertices.size(), before.mesh.vertices.size());
  EXPECT_EQ(r.sphere_components, 1);
}

}  // namespace
}  // namespace inc
