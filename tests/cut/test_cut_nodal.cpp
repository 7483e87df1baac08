// Cut spheres -> nodal points -> re-packed spheres: mass, visibility, separation and determinism on a lattice block.
#include <gtest/gtest.h>

#include <cmath>

#include "cpu_fallback/neighbor_bruteforce.h"
#include "host/cut/cut_nodal_points.h"
#include "model/input_error.h"
#include "tests/support/cut_fixtures.h"

namespace inc {
namespace {

using cuttest::latticeBlock;
using cuttest::linkComponents;
using cuttest::straightSweep;

// Block 12 x 8 x 6 spheres (0.12 x 0.08 x 0.06 m); the cut is z = 0, between two sphere layers.
SweptSurface fullCut() { return straightSweep(-0.1, 0.1, -0.1, 0.1); }
SweptSurface partialCut() { return straightSweep(-0.1, 0.0, -0.1, 0.1); }

TEST(CutNodal, CutSpheresBecomeLatticePointsWithTheirMassShared) {
  const MetaballModel m = latticeBlock(12, 8, 6);
  const SphereCutResult r = cutSpheres(m, fullCut());
  // The two middle layers (|z| = 0.005 < r = 0.0075) are cut, the others (|z| >= 0.015) are not.
  ASSERT_EQ(r.cut.size(), 2u * 12u * 8u);
  for (auto i : r.cut) EXPECT_LT(std::fabs(m.rest_centers[i].z), 0.0075);
  EXPECT_EQ(r.spheres.size(), m.size() - r.cut.size());
  // 4 cells per diameter: 32 of the 64 cell centres lie inside the ball (offsets 0.25 r and 0.75 r).
  EXPECT_EQ(r.points.size(), r.cut.size() * 32u);
  for (std::size_t p = 0; p < r.points.size(); ++p) {
    const int s = r.points.source_sphere[p];
    EXPECT_LT(norm(r.points.positions[p] - m.rest_centers[s]), m.rest_radii[s]);
    EXPECT_NEAR(r.points.masses[p], m.masses[s] / 32.0, 1e-15);
    EXPECT_EQ(r.points.side[p], r.points.positions[p].z > 0 ? 1 : -1);
  }
  const double before = totalMass(m), after = totalMass(r.spheres) + totalMass(r.points);
  EXPECT_NEAR(after / before, 1.0, 1e-12);
}

TEST(CutNodal, NoMlsNeighbourAcrossTheCut) {
  const MetaballModel m = latticeBlock(12, 8, 6);
  const SweptSurface s = fullCut();
  const SphereCutResult r = cutSpheres(m, s);
  const double h = 2.5 * r.points.spacing;
  std::size_t removed = 0;
  const NeighborLists vis = visibleNodalNeighbours(r.points, h, s, &removed);
  EXPECT_GT(removed, 0u);
  // Reference: every pair within h on the same side (the cut spans the block, so "crosses" == "other side").
  const NeighborLists all =
      cpu::bruteForceNeighbors(r.points.positions, r.points.positions, std::vector<double>{h}, true);
  std::size_t same_side = 0;
  for (std::size_t q = 0; q < all.queryCount(); ++q)
    for (auto k = all.offsets[q]; k < all.offsets[q + 1]; ++k)
      same_side += r.points.side[q] == r.points.side[all.indices[k]];
  EXPECT_EQ(vis.indices.size(), same_side);
  EXPECT_EQ(removed, all.indices.size() - same_side);
  for (std::size_t q = 0; q < vis.queryCount(); ++q)
    for (auto k = vis.offsets[q]; k < vis.offsets[q + 1]; ++k) {
      ASSERT_EQ(r.points.side[q], r.points.side[vis.indices[k]]);
      ASSERT_FALSE(segmentCrossesSweptSurface(s, r.points.positions[q], r.points.positions[vis.indices[k]]));
    }
}

TEST(CutNodal, MassConservedThroughSpheresPointsSpheresAndFullCutSeparates) {
  const MetaballModel m = latticeBlock(12, 8, 6);
  const SweptSurface s = fullCut();
  SphereCutResult r = cutSpheres(m, s);
  EXPECT_EQ(linkComponents(m), 1);
  const std::size_t added = repackSpheres(r.spheres, r.points, s);
  EXPECT_GT(added, 0u);
  EXPECT_LT(added, r.points.size());
  EXPECT_NEAR(totalMass(r.spheres) / totalMass(m), 1.0, 1e-12);  // the issue asks 1e-6
  for (std::size_t l = 0; l < r.spheres.links.size(); ++l) {
    const auto& e = r.spheres.links[l];
    ASSERT_LT(e[0], e[1]);
    ASSERT_FALSE(segmentCrossesSweptSurface(s, r.spheres.rest_centers[e[0]], r.spheres.rest_centers[e[1]]));
    ASSERT_EQ(r.spheres.rest_centers[e[0]].z > 0, r.spheres.rest_centers[e[1]].z > 0);
  }
  for (double mass : r.spheres.masses) EXPECT_GT(mass, 0.0);
  EXPECT_EQ(linkComponents(r.spheres), 2);
  // The new spheres of each side cover at least 95 % of its nodal points (Algorithm 1's balls are inscribed in
  // the point groups, docs/cutting.md).
  std::size_t covered = 0;
  for (std::size_t p = 0; p < r.points.size(); ++p) {
    bool in = false;
    for (std::size_t i = r.spheres.size() - added; i < r.spheres.size() && !in; ++i)
      in = norm(r.points.positions[p] - r.spheres.rest_centers[i]) <= r.spheres.rest_radii[i] + 1e-15 &&
           (r.spheres.rest_centers[i].z > 0) == (r.points.side[p] > 0);
    covered += in;
  }
  EXPECT_GE(double(covered), 0.95 * double(r.points.size()));
}

TEST(CutNodal, PartialCutLeavesOnePiece) {
  const MetaballModel m = latticeBlock(12, 8, 6);
  const SweptSurface s = partialCut();
  SphereCutResult r = cutSpheres(m, s);
  // The two middle layers for the 6 columns with x < 0, plus the column at x = 0.005, whose spheres are
  // sqrt(0.005^2 + 0.005^2) = 0.00707 m < r = 0.0075 m from the blade's end line x = 0.
  EXPECT_EQ(r.cut.size(), 2u * 7u * 8u);
  repackSpheres(r.spheres, r.points, s);
  EXPECT_NEAR(totalMass(r.spheres) / totalMass(m), 1.0, 1e-12);
  EXPECT_EQ(linkComponents(r.spheres), 1);
}

TEST(CutNodal, SameCutGivesBitIdenticalResult) {
  const MetaballModel m = latticeBlock(10, 6, 6);
  std::vector<BladePose> poses;
  for (int k = 0; k <= 8; ++k) {  // a curved, tilted cut
    const double x = -0.08 + 0.02 * k, z = 0.004 * std::sin(0.7 * k);
    poses.push_back({Vec3d(x, -0.1, z - 0.01), Vec3d(x, 0.1, z + 0.01)});
  }
  const SweptSurface s = sweepSurface(poses);
  SphereCutResult a = cutSpheres(m, s), b = cutSpheres(m, s);
  repackSpheres(a.spheres, a.points, s);
  repackSpheres(b.spheres, b.points, s);
  ASSERT_EQ(a.spheres.size(), b.spheres.size());
  ASSERT_EQ(a.spheres.links, b.spheres.links);
  for (std::size_t i = 0; i < a.spheres.size(); ++i) {
    ASSERT_EQ(norm(a.spheres.rest_centers[i] - b.spheres.rest_centers[i]), 0.0);
    ASSERT_EQ(a.spheres.rest_radii[i], b.spheres.rest_radii[i]);
    ASSERT_EQ(a.spheres.masses[i], b.spheres.masses[i]);
  }
  EXPECT_NEAR(totalMass(a.spheres) / totalMass(m), 1.0, 1e-12);
}

TEST(CutNodal, BadOptionsAreInputErrors) {
  const MetaballModel m = latticeBlock(3, 3, 3);
  CutOptions o;
  o.samples_per_diameter = 0;
  EXPECT_THROW(cutSpheres(m, fullCut(), o), InputError);
}

}  // namespace
}  // namespace inc
