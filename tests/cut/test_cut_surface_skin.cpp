// Split surfaces in use: skin weights never cross a cut; curved and partial scripted cuts in DissectionSimulation.
#include <gtest/gtest.h>

#include <cmath>

#include "host/assembly/organ_shapes.h"
#include "host/cut/cut_surface_state.h"
#include "host/scene/scene_compile.h"
#include "host/sim/dissection_simulation.h"
#include "tests/support/cut_block_scene.h"
#include "tests/support/cut_fixtures.h"
#include "tests/support/cut_surface_fixtures.h"

namespace inc {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(CutSurfaceSkin, NoSkinWeightCrossesAPartialThenACurvedCut) {
  const MetaballModel spheres = cuttest::latticeBlock(10, 8, 6);  // centres x +-0.045, y +-0.035, z +-0.025
  CutSurfaceState state = cutSurfaceState(makeBoxMesh(Vec3d(0.05, 0.04, 0.03), 8));
  // 1: a vertical blade enters through x = -0.05 along y = 2.1 mm and stops at x = 0.012 (a slit);
  // 2: a vertical blade along an arc through the whole block.
  const std::vector<SweptSurface> cuts = {
      cuttest::straightBladeSweep(Vec3d(-0.1, 0.0021, -0.1), Vec3d(-0.1, 0.0021, 0.1), Vec3d(0.112, 0, 0), 5),
      cuttest::arcSweep(0.0, -0.1, 0.085, kPi / 2 + 0.9, kPi / 2 - 0.9, 20, -0.1, 0.1)};
  for (std::size_t c = 0; c < cuts.size(); ++c) {
    const SurfaceSplit r = applySurfaceCut(state, cuts[c]);
    ASSERT_TRUE(r.split) << c;
    cuttest::expectClosedManifold(state.mesh, "after cut " + std::to_string(c));
    std::vector<SweptSurface> so_far(cuts.begin(), cuts.begin() + std::ptrdiff_t(c) + 1);
    const SkinBinding b = bindSkinAcrossCuts(state, spheres, so_far, 4);
    ASSERT_EQ(b.vertexCount(), int(state.mesh.vertices.size()));
    std::size_t weights = 0;
    for (int v = 0; v < b.vertexCount(); ++v)
      for (int j = 0; j < b.k; ++j) {
        if (b.weight[std::size_t(v * b.k + j)] <= 0.0) continue;
        ++weights;
        const Vec3d& centre = spheres.rest_centers[std::size_t(b.sphere[std::size_t(v * b.k + j)])];
        for (const auto& cut : so_far)
          EXPECT_FALSE(segmentCrossesSweptSurface(cut, state.probe[std::size_t(v)], centre))
              << "vertex " << v << " cut " << c;
      }
    EXPECT_GT(weights, std::size_t(b.vertexCount()));
  }
  // The first cut's walls: a wall vertex on the +y side binds only to spheres with y > 2.1 mm, and so on.
  const CutSurfaceState first = [&] {
    CutSurfaceState s = cutSurfaceState(makeBoxMesh(Vec3d(0.05, 0.04, 0.03), 8));
    applySurfaceCut(s, cuts[0]);
    return s;
  }();
  const SkinBinding b = bindSkinAcrossCuts(first, spheres, {cuts[0]}, 4);
  int checked = 0;
  for (int v = 0; v < b.vertexCount(); ++v) {
    const Vec3d& x = first.mesh.vertices[std::size_t(v)];
    if (std::fabs(x.y - 0.0021) > 1e-9 || x.x > -0.005) continue;  // wall vertices well behind the front
    const double side = first.probe[std::size_t(v)].y - 0.0021;
    for (int j = 0; j < b.k; ++j)
      if (b.weight[std::size_t(v * b.k + j)] > 0.0) {
        EXPECT_GT((spheres.rest_centers[std::size_t(b.sphere[std::size_t(v * b.k + j)])].y - 0.0021) * side, 0.0) << v;
        ++checked;
      }
  }
  EXPECT_GT(checked, 20);
}

// The block of test_cut_dissection.cpp (6 x 4 x 3 cm, 1 cm spheres, no gravity) cut by a vertical blade whose
// centre runs along an arc of radius 6.5 cm (keyframes every 0.1 rad) from angle pi/2 + 0.7 to `end`.
Scene arcCutScene(double end_angle) {
  Scene s = cuttest::dissectionBlock("<test:arc_cut>");
  ToolSpec t = cuttest::scalpel({});
  const double a0 = kPi / 2 + 0.7;
  const int n = int(std::lround((a0 - end_angle) / 0.1));
  for (int k = 0; k <= n; ++k) {
    const double a = a0 + (end_angle - a0) * k / n;
    t.path.push_back(
        {0.05 + 0.1 * k / n, Vec3d(0.065 * std::cos(a), -0.06 + 0.065 * std::sin(a), 0.0), Vec3d(0, 0, 1)});
  }
  s.tools = {t};
  return s;
}

TEST(CutSurfaceSkin, CurvedAndPartialScriptedCutsSplitTheSimulatedSurface) {
  for (const bool through : {true, false}) {
    auto sim = makeDissectionSimulation(compileScene(arcCutScene(through ? kPi / 2 - 0.7 : kPi / 2)), BackendKind::Cpu,
                                        Precision::Float64);
    FrameReport rep;
    for (int f = 0; f < 14; ++f) {
      rep = sim->advance(1.0 / 60.0);
      ASSERT_TRUE(rep.finite) << f;
    }
    EXPECT_EQ(rep.counters["cuts_applied"], 1.0);
    EXPECT_EQ(rep.counters["surface_split"], 1.0) << through;
    TriangleMesh surf;
    ASSERT_TRUE(sim->currentSurface(surf));
    const MeshReport m = cuttest::expectClosedManifold(surf, through ? "arc through" : "arc partial");
    // A cut right through leaves two pieces, a partial one a single surface with a slit.
    EXPECT_EQ(m.components, through ? 2 : 1);
    EXPECT_EQ(rep.counters["surface_components"], through ? 2.0 : 1.0);
    // At rest (no loads) the skinned surface is the rest surface: the block's volume, the walls cancelling.
    EXPECT_NEAR(m.signed_volume / (0.06 * 0.04 * 0.03), 1.0, 1e-9);
    std::vector<std::uint8_t> wall;
    sim->cutWallTriangles(wall);
    ASSERT_EQ(wall.size(), surf.triangles.size());
    std::size_t walls = 0;
    for (std::size_t t = 0; t < wall.size(); ++t) {
      if (!wall[t]) continue;
      ++walls;
      // Wall triangles lie on the blade's cylinder (radius 6.5 cm about (0, -6 cm)) to within the chords of the
      // sweep (one strip per 1/60 s frame spans ~0.23 rad: sagitta 0.44 mm) and the crossings' snap distance.
      for (int c : surf.triangles[t]) {
        const Vec3d& p = surf.vertices[std::size_t(c)];
        EXPECT_NEAR(std::hypot(p.x, p.y + 0.06), 0.065, 2e-3);
      }
    }
    EXPECT_GT(walls, 20u);
  }
}

}  // namespace
}  // namespace inc
