// The surface opened along a stroke's sweep while the blade is still in (cutting.open_surface_frames): a closed
// slit shown a fixed number of frames after each opening starts, each side following its own tissue, and nothing
// the simulation computes changed by it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "host/io/mesh.h"
#include "host/scene/scene_compile.h"
#include "host/sim/dissection_simulation.h"
#include "tests/support/cut_block_scene.h"
#include "tests/support/held_idle_workers.h"

namespace inc {
namespace {

constexpr double kDt = 1.0 / 60.0;

// The fixture's block cut through by 0.3 s (the blade is in the block from about frame 5 to frame 15).
Scene block(int open_frames, bool gravity) {
  Scene s = cuttest::cutBlockScene(0.3, gravity, "<test:surface_opening>");
  s.cutting.open_surface_frames = open_frames;
  return s;
}

struct Frame {
  FrameReport report;
  TriangleMesh surface;
  std::vector<std::uint8_t> wall;
};

std::vector<Frame> record(const Scene& s, int frames, std::vector<Vec3d>* positions = nullptr) {
  std::vector<Frame> out;
  auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  for (int f = 0; f < frames; ++f) {
    Frame fr;
    fr.report = sim->advance(kDt);
    EXPECT_TRUE(fr.report.finite) << f;
    EXPECT_TRUE(sim->currentSurface(fr.surface));
    sim->cutWallTriangles(fr.wall);
    out.push_back(std::move(fr));
  }
  if (positions) sim->currentPositions(*positions);
  return out;
}

double counter(const Frame& f, const char* key) { return f.report.counters.at(key); }

// While the blade is in, the shown surface is the block slit along the sweep so far: closed, manifold, one piece,
// with wall triangles, growing as the blade advances; each opening is shown exactly `open` frames after it starts
// (pending that many frames). At rest (no load) it stays at rest (1e-9 m). The stroke's end is the same as without
// the openings: the same sphere positions and surface, bit for bit.
TEST(CutSurfaceOpening, SlitShownDuringTheStrokeAndTheEndUnchanged) {
  const int open = 2, frames = 22;
  std::vector<Vec3d> x_plain, x_open;
  const std::vector<Frame> plain = record(block(0, false), frames, &x_plain);
  const std::vector<Frame> opened = record(block(open, false), frames, &x_open);
  int shown = 0, first_shown = -1, changes = 0, end = -1;
  std::size_t walls_before = 0;
  for (int f = 0; f < frames; ++f) {
    const Frame& fr = opened[std::size_t(f)];
    if (end < 0 && counter(fr, "cuts_applied") > 0) end = f;
    if (end >= 0 || counter(fr, "surface_opened") == 0) continue;
    ++shown;
    if (first_shown < 0) first_shown = f;
    const MeshReport m = analyzeMesh(fr.surface);
    EXPECT_TRUE(m.closed()) << f;
    EXPECT_EQ(m.components, 1) << f;  // a slit, not yet through
    const std::size_t walls = std::size_t(std::count(fr.wall.begin(), fr.wall.end(), std::uint8_t(1)));
    EXPECT_GT(walls, 0u) << f;
    EXPECT_GE(walls, walls_before) << f;
    EXPECT_EQ(fr.wall.size(), fr.surface.triangles.size()) << f;
    EXPECT_GT(fr.surface.triangles.size(), plain[std::size_t(f)].surface.triangles.size()) << f;
    // A new opening is shown only every `open` frames: each takes that long from its start to being shown, and
    // the next starts at the frame it is shown.
    if (f > first_shown && walls != walls_before) {
      EXPECT_EQ((f - first_shown) % open, 0) << f;
      ++changes;
    }
    walls_before = walls;
  }
  EXPECT_GE(changes, 3);
  ASSERT_GT(end, 0);
  EXPECT_GE(shown, 4);
  for (int f = 0; f < frames; ++f) {
    EXPECT_LT(opened[std::size_t(f)].report.max_displacement, 1e-9) << f;
    EXPECT_EQ(counter(opened[std::size_t(f)], "nodal_points"), counter(plain[std::size_t(f)], "nodal_points")) << f;
  }
  // From the stroke's end on: the openings are gone, the same split surface and spheres as without them.
  for (int f = end; f < frames; ++f) EXPECT_EQ(counter(opened[std::size_t(f)], "surface_opened"), 0.0) << f;
  EXPECT_EQ(opened.back().surface.triangles, plain.back().surface.triangles);
  EXPECT_EQ(opened.back().surface.vertices.size(), plain.back().surface.vertices.size());
  for (std::size_t v = 0; v < plain.back().surface.vertices.size(); ++v)
    ASSERT_EQ(norm(opened.back().surface.vertices[v] - plain.back().surface.vertices[v]), 0.0) << v;
  ASSERT_EQ(x_open.size(), x_plain.size());
  for (std::size_t i = 0; i < x_open.size(); ++i) ASSERT_EQ(norm(x_open[i] - x_plain[i]), 0.0) << i;
}

// Each side of the slit follows its own tissue: the block's spheres below the blade's plane held, gravity on.
// Before the stroke ends, the wall vertices of the free side sag (over 1 mm) where the blade has passed, and those
// of the held side stay where the held spheres keep them (1e-6 m): the slit opens.
TEST(CutSurfaceOpening, EachSideOfTheSlitFollowsItsOwnTissue) {
  Scene s = block(2, true);
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(1, -0.003, 1)}};  // the centres on the far side of the blade's plane y = 2 mm
  const int frames = 15;
  const std::vector<Frame> run = record(s, frames);
  const Frame& last = run.back();
  ASSERT_EQ(counter(last, "cuts_applied"), 0.0);  // the blade is still in
  ASSERT_EQ(counter(last, "surface_opened"), 1.0);
  // Rest positions of the shown mesh's wall vertices, from a run at rest with the same openings.
  Scene rest = s;
  rest.solver.gravity = Vec3d(0, 0, 0);
  const std::vector<Frame> still = record(rest, frames);
  ASSERT_EQ(still.back().surface.vertices.size(), last.surface.vertices.size());
  double held_max = 0, free_min = 1e9;
  int held = 0, freed = 0;
  const TriangleMesh& r = still.back().surface;
  for (std::size_t t = 0; t < last.surface.triangles.size(); ++t) {
    if (!last.wall[t]) continue;
    // A wall's two faces share their rest positions; the face's outward normal says its side: +y faces belong to
    // the piece below the blade's plane (held), -y faces to the one above (free).
    const auto& tri = last.surface.triangles[t];
    const Vec3d a = r.vertices[std::size_t(tri[0])], b = r.vertices[std::size_t(tri[1])],
                c = r.vertices[std::size_t(tri[2])];
    const Vec3d n = cross(b - a, c - a);
    if (std::abs(n.y) < 0.5 * norm(n)) continue;  // not on the blade's plane
    for (int k = 0; k < 3; ++k) {
      const Vec3d x0 = r.vertices[std::size_t(tri[k])];
      if (x0.x > 0.0) continue;  // the slit's part the blade passed long enough ago to open (it moves along +x)
      const double sag = x0.z - last.surface.vertices[std::size_t(tri[k])].z;
      if (n.y > 0) {
        held_max = std::max(held_max, std::abs(sag));
        ++held;
      } else {
        free_min = std::min(free_min, sag);
        ++freed;
      }
    }
  }
  ASSERT_GT(held, 5);
  ASSERT_GT(freed, 5);
  // Measured: 2e-19 m held, 13 mm free. Bound to the spheres without the partial sweep in the visibility test
  // (checked by mutation), the held wall sags with the free side: 19 mm.
  EXPECT_LT(held_max, 1e-6);
  EXPECT_GT(free_min, 1e-3);
}

// An opening worker starved past the due frame (held, as a busy machine would) is waited for no longer than
// patience(): the due frame computes the opening itself, and the next ones, while the worker is still held, are
// computed when due without it. What is shown is the same, frame by frame, bit for bit.
TEST(CutSurfaceOpening, StarvedWorkerIsReplacedByTheDueFrame) {
  const int open = 2, frames = 20;
  const std::vector<Frame> plain = record(block(open, true), frames);
  auto sim = makeDissectionSimulation(compileScene(block(open, true)), BackendKind::Cpu, Precision::Float64);
  cuttest::HeldIdleWorkers held;
  double here = 0;
  for (int f = 0; f < frames; ++f) {
    const FrameReport rep = sim->advance(kDt);
    ASSERT_TRUE(rep.finite) << f;
    here = rep.counters.at("surface_open_here");
    EXPECT_EQ(rep.counters.at("surface_opened"), plain[std::size_t(f)].report.counters.at("surface_opened")) << f;
    TriangleMesh surface;
    ASSERT_TRUE(sim->currentSurface(surface));
    ASSERT_EQ(surface.triangles, plain[std::size_t(f)].surface.triangles) << f;
    ASSERT_EQ(surface.vertices.size(), plain[std::size_t(f)].surface.vertices.size()) << f;
    for (std::size_t v = 0; v < surface.vertices.size(); ++v)
      ASSERT_EQ(norm(surface.vertices[v] - plain[std::size_t(f)].surface.vertices[v]), 0.0) << f << " " << v;
  }
  EXPECT_GE(here, 3.0);       // every opening of the stroke was computed on the frame's thread
  EXPECT_EQ(held.held(), 1);  // the one started on the worker waited at the gate throughout
}

}  // namespace
}  // namespace inc
