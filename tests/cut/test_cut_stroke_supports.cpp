// StrokeSupports and NodalRegion's supports over a stroke: the incremental lists equal visibleSupports from scratch.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "host/cut/cut_nodal_points.h"
#include "host/cut/cut_nodal_region.h"
#include "host/cut/cut_stroke_supports.h"
#include "tests/support/cut_fixtures.h"

namespace inc {
namespace {

// A vertical blade (z from -0.03 to 0.03 m) along an arc of radius 6 cm about (0, -0.06): pose k of `steps` at
// angle -1 + 1.3 k / steps rad, from outside the block's -x end to beyond its middle (a partial, curved stroke).
BladePose arcPose(int k, int steps) {
  const double a = -1.0 + 1.3 * double(k) / steps, r = 0.06;
  const Vec3d p(r * std::sin(a), -0.06 + r * std::cos(a), 0.0);
  return {p + Vec3d(0, 0, -0.03), p + Vec3d(0, 0, 0.03)};
}

// An earlier cut: the plane x = 1 mm from y = -4 cm to 0.5 cm (partial), blade along z.
SweptSurface earlierCut() {
  return sweepSurface({{Vec3d(0.001, -0.04, -0.03), Vec3d(0.001, -0.04, 0.03)},
                       {Vec3d(0.001, 0.005, -0.03), Vec3d(0.001, 0.005, 0.03)}});
}

// The strip the last extendSweptSurface added (what the simulation hands to cutSupports).
SweptSurface lastStrip(const SweptSurface& s, std::size_t triangles_before) {
  SweptSurface f;
  const int nv = int(s.vertices.size());
  f.vertices.assign(s.vertices.end() - 4, s.vertices.end());
  for (std::size_t t = triangles_before; t < s.triangles.size(); ++t)
    f.triangles.push_back({s.triangles[t][0] - nv + 4, s.triangles[t][1] - nv + 4, s.triangles[t][2] - nv + 4});
  return f;
}

// Same offsets, same indices (so the same order) and the same count of dropped entries.
void expectSameLists(const NeighborLists& got, std::size_t got_removed, const NeighborLists& want,
                     std::size_t want_removed, const std::string& where) {
  ASSERT_EQ(got.offsets, want.offsets) << where;
  ASSERT_EQ(got.indices, want.indices) << where;
  EXPECT_EQ(got_removed, want_removed) << where;
}

bool sameLists(const NeighborLists& a, const NeighborLists& b) {
  return a.offsets == b.offsets && a.indices == b.indices;
}

// The dissection's sequence on a 10 x 6 x 4 block with an earlier cut: a curved stroke in 30 frames, each either
// converting the spheres its new strip enters (convert with the whole stroke) or cutting the supports by the new
// strip alone (cutSupports). After every frame the region's supports are the lists visibleSupports computes from
// scratch for its points and the cuts (earlier + stroke so far), bit for bit, and so is the dropped count. The
// comparison is with real data: the earlier cut and the last strip each change the from-scratch lists (checked),
// the stroke converts several times and cuts supports without converting too.
TEST(CutStrokeSupports, IncrementalSupportsEqualVisibleSupportsOverACurvedStroke) {
  const MetaballModel m = cuttest::latticeBlock(10, 6, 4);
  const SweptSurface earlier = earlierCut();
  NodalRegionSettings s;
  s.samples_per_diameter = 4;
  s.backend = BackendKind::Cpu;
  s.precision = Precision::Float64;
  s.mls.source = "<test stroke supports>";
  s.mls.material.youngs_modulus_pa = 5.0e3;
  s.mls.gravity = Vec3d(0, 0, 0);
  NodalRegion region(m, s, {&earlier});
  const auto atRest = [&](std::int32_t b) {
    ConvertedSphereState st;
    st.position = m.rest_centers[std::size_t(b)];
    return st;
  };
  const int steps = 30;
  SweptSurface stroke;
  stroke.vertices = {arcPose(0, steps).base, arcPose(0, steps).tip};
  int conversions = 0, strip_cuts = 0, earlier_mattered = 0, strip_mattered = 0;
  for (int k = 1; k <= steps; ++k) {
    const std::size_t before = stroke.triangles.size();
    extendSweptSurface(stroke, arcPose(k, steps));
    const SweptSurface fresh = lastStrip(stroke, before);
    std::vector<std::int32_t> hit = findCutSpheres(fresh, m.rest_centers, m.rest_radii);
    hit.erase(std::remove_if(hit.begin(), hit.end(), [&](std::int32_t b) { return region.role(b) == SphereRole::Cut; }),
              hit.end());
    if (!hit.empty()) {
      region.convert(hit, atRest, stroke);
      ++conversions;
    } else if (region.active()) {
      strip_cuts += region.cutSupports(fresh) > 0;
    }
    if (!region.active()) continue;
    const double h = s.mls.support_factor * region.pointSpacing();
    std::size_t removed = 0;
    const NeighborLists want = visibleSupports(region.restPoints(), h, {&earlier, &stroke}, &removed);
    expectSameLists(region.supports(), region.supportsRemoved(), want, removed, "frame " + std::to_string(k));
    earlier_mattered += !sameLists(want, visibleSupports(region.restPoints(), h, {&stroke}));
    SweptSurface without_last = stroke;
    without_last.triangles.resize(before);
    strip_mattered += !sameLists(want, visibleSupports(region.restPoints(), h, {&earlier, &without_last}));
  }
  EXPECT_GE(conversions, 6);
  EXPECT_GE(strip_cuts, 6);
  EXPECT_GE(earlier_mattered, 8);
  EXPECT_GE(strip_mattered, 20);
  EXPECT_GT(region.pointCount(), 500u);
}

// StrokeSupports alone on a random cloud (no lattice symmetry: pairs at every length and angle to the cuts):
// points added in batches, strips added between and with them, two earlier cuts; equal to visibleSupports after
// every step. A stroke that does not extend the one seen starts over, and equals visibleSupports too.
TEST(CutStrokeSupports, RandomCloudInBatchesEqualsVisibleSupports) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.03, 0.03);
  std::vector<Vec3d> all(2400);
  for (auto& p : all) p = Vec3d(u(rng), u(rng), u(rng));
  const SweptSurface e1 = sweepSurface(
      {{Vec3d(-0.04, 0.004, -0.04), Vec3d(-0.04, 0.004, 0.04)}, {Vec3d(0.01, 0.004, -0.04), Vec3d(0.01, 0.004, 0.04)}});
  const SweptSurface e2 = sweepSurface(
      {{Vec3d(0.007, -0.04, -0.04), Vec3d(0.007, -0.04, 0.04)}, {Vec3d(0.007, 0.04, -0.04), Vec3d(0.007, 0.04, 0.04)}});
  const double h = 0.006;
  StrokeSupports sup(h, {&e1, &e2});
  // A tilted blade along a wavy path in x.
  const auto pose = [](int k) {
    const double x = -0.04 + 0.005 * k, y = 0.012 * std::sin(40.0 * x);
    return BladePose{Vec3d(x, y, -0.04), Vec3d(x, y + 0.01, 0.04)};
  };
  SweptSurface stroke;
  stroke.vertices = {pose(0).base, pose(0).tip};
  std::vector<Vec3d> x;
  int dropped_by_strips = 0;
  for (int k = 1; k <= 14; ++k) {
    const std::size_t before = stroke.triangles.size();
    extendSweptSurface(stroke, pose(k));
    if (k % 3 == 2 && !x.empty()) {
      dropped_by_strips += sup.extend(x, lastStrip(stroke, before)) > 0;  // a strip, no new points
    } else {
      const std::size_t add = k == 1 ? 600 : 150;
      for (std::size_t i = 0; i < add && x.size() < all.size(); ++i) x.push_back(all[x.size()]);
      sup.update(x, stroke);
    }
    std::size_t removed = 0;
    const NeighborLists want = visibleSupports(x, h, {&e1, &e2, &stroke}, &removed);
    expectSameLists(sup.lists(), sup.removed(), want, removed, "step " + std::to_string(k));
  }
  EXPECT_GE(dropped_by_strips, 3);
  // A different stroke (not an extension): the lists start over against it.
  const SweptSurface other = cuttest::straightSweep(-0.05, 0.05, -0.05, 0.05);
  sup.update(x, other);
  std::size_t removed = 0;
  const NeighborLists want = visibleSupports(x, h, {&e1, &e2, &other}, &removed);
  expectSameLists(sup.lists(), sup.removed(), want, removed, "other stroke");
  EXPECT_GT(removed, 0u);
}

}  // namespace
}  // namespace inc
