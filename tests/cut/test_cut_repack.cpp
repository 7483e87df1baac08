// Algorithm 1 re-packing: classification, eq. 14 spacing, exact mass and cover, isolated points, and twenty
// successive cuts with a bounded sphere count and a covered tissue.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "host/cut/cut_nodal_points.h"
#include "host/cut/cut_repack.h"
#include "tests/support/cut_fixtures.h"

namespace inc {
namespace {

// The cut spheres' points, plus the kept spheres' (every kept sphere within a support of them, sampled alike) as
// context, as the dissection model gives them (its interface spheres' points).
RepackPoints repackInput(const SphereCutResult& cr, const std::vector<const SweptSurface*>& cuts) {
  RepackPoints rp;
  rp.rest = cr.points.positions;
  rp.mass = cr.points.masses;
  rp.context.assign(rp.rest.size(), 0);
  rp.spacing = cr.points.spacing;
  rp.support = 2.0 * cr.points.spacing;
  for (std::size_t j = 0; j < cr.spheres.size(); ++j) {
    bool near = false;
    for (std::size_t i = 0; i < cr.points.size() && !near; ++i)
      near = norm(cr.points.positions[i] - cr.spheres.rest_centers[j]) < cr.spheres.rest_radii[j] + rp.support;
    if (!near) continue;
    for (const Vec3d& x : sampleSphere(cr.spheres.rest_centers[j], cr.spheres.rest_radii[j], 4, cuts)) {
      rp.rest.push_back(x);
      rp.mass.push_back(0.0);
      rp.context.push_back(1);
    }
  }
  rp.visible = visibleSupports(rp.rest, rp.support, cuts);
  return rp;
}

// A block cut through at z = 0: two groups; the layer on the cut wall is boundary, medial points lie inside;
// eq. 14's d is half the largest medial distance to the cut; the spheres kept are farther apart than d, within
// the budget, hold every point's mass (1e-12): each point's goes to its nearest centre, on its side; the balls
// contain at least 95 % of the points.
TEST(CutRepack, SlabGroupsAreClassifiedDownSampledAndCovered) {
  const MetaballModel m = cuttest::latticeBlock(10, 6, 4);
  const SweptSurface s = cuttest::straightSweep(-0.1, 0.1, -0.1, 0.1);
  const SphereCutResult cr = cutSpheres(m, s);
  const RepackPoints rp = repackInput(cr, {&s});
  RepackSettings set;
  set.reference_mass = m.masses[0];
  set.max_radius = 1.5 * m.rest_radii[0];
  const RepackResult r = packNodalPoints(rp, s, set);
  EXPECT_EQ(r.groups, 2);
  const std::size_t np = cr.points.size();
  EXPECT_EQ(r.boundary + r.medial + r.middle, np);
  EXPECT_GT(r.medial, 0u);
  EXPECT_GT(r.middle, 0u);
  double smax = 0.0, mass = 0.0;
  std::size_t inside = 0;
  for (std::size_t i = 0; i < np; ++i) {
    if (std::fabs(rp.rest[i].z) < 0.5 * rp.spacing) {  // the layer on the cut wall
      EXPECT_EQ(r.point_class[i], kRepackBoundary) << i;
    }
    if (r.point_class[i] == kRepackMedial) {
      EXPECT_GT(std::fabs(rp.rest[i].z), 0.5 * rp.spacing) << i;
      smax = std::max(smax, std::fabs(rp.rest[i].z));
    }
    const std::size_t o = std::size_t(r.owner[i]);
    EXPECT_EQ(r.centres[o].z > 0, rp.rest[i].z > 0) << i;
    for (std::size_t q = 0; q < r.centres.size(); ++q)
      if ((r.centres[q].z > 0) == (rp.rest[i].z > 0)) {
        ASSERT_LE(norm(rp.rest[i] - r.centres[o]), norm(rp.rest[i] - r.centres[q])) << i;
      }
    for (std::size_t q = 0; q < r.centres.size(); ++q)
      if (norm(rp.rest[i] - r.centres[q]) <= r.radii[q] && (r.centres[q].z > 0) == (rp.rest[i].z > 0)) {
        ++inside;
        break;
      }
    mass += rp.mass[i];
  }
  EXPECT_NEAR(r.spacing_max, std::max(rp.spacing, 0.5 * smax), 1e-12);
  EXPECT_GE(double(inside), 0.95 * double(np));
  const double packed_mass = std::accumulate(r.masses.begin(), r.masses.end(), 0.0);
  EXPECT_NEAR(packed_mass / mass, 1.0, 1e-12);
  // Budget: each side holds half the cut spheres' mass, so at most cut / 2 (+1 for rounding) spheres per side.
  EXPECT_LE(r.centres.size(), cr.cut.size() + 2);
  EXPECT_GT(r.packed, r.centres.size());  // eq. 14's spacing packs more than the budget: small ones merged
  EXPECT_EQ(r.merged, r.packed - r.centres.size());
  EXPECT_GT(r.merge_spacing_max, r.spacing_max);
  for (std::size_t a = 0; a < r.centres.size(); ++a)
    for (std::size_t b = a + 1; b < r.centres.size(); ++b)
      if ((r.centres[a].z > 0) == (r.centres[b].z > 0)) {
        EXPECT_GT(norm(r.centres[a] - r.centres[b]), r.spacing_min);
      }
  std::printf(
      "[repack slab] %zu points: %zu boundary, %zu medial, %zu middle; d = %.4f m; packed %zu, kept %zu "
      "(cut spheres %zu)\n",
      np, r.boundary, r.medial, r.middle, r.spacing_max, r.packed, r.centres.size(), cr.cut.size());
}

// A point beyond the support of every other point (isolated) is merged into the nearest sphere it sees; with a
// cut between them, it becomes a small sphere of its own that contains it. Mass is exact either way.
TEST(CutRepack, IsolatedPointsAreMergedIntoTheNearestVisibleSphere) {
  const MetaballModel m = cuttest::latticeBlock(6, 4, 4);
  const SweptSurface s = cuttest::straightSweep(-0.1, 0.1, -0.1, 0.1);
  const SphereCutResult cr0 = cutSpheres(m, s);
  for (int blocked = 0; blocked < 2; ++blocked) {
    SphereCutResult cr = cr0;
    NodalPoints& p = cr.points;
    const Vec3d lone(0.0, 0.05, 0.004);  // above the cut, 2 cm beyond the block's side (y = 0.02)
    p.positions.push_back(lone);
    p.masses.push_back(1e-4);
    p.source_sphere.push_back(0);
    p.side.push_back(1);
    const std::vector<BladePose> poses{{Vec3d(-0.1, 0.035, -0.1), Vec3d(-0.1, 0.035, 0.1)},
                                       {Vec3d(0.1, 0.035, -0.1), Vec3d(0.1, 0.035, 0.1)}};
    const SweptSurface wall = sweepSurface(poses);  // the plane y = 3.5 cm, between the lone point and the block
    std::vector<const SweptSurface*> cuts{&s};
    if (blocked) cuts.push_back(&wall);
    RepackPoints rp = repackInput(cr, cuts);
    RepackSettings set;
    set.reference_mass = m.masses[0];
    if (blocked) set.earlier_cuts = {&wall};
    const RepackResult r = packNodalPoints(rp, s, set);
    const std::size_t o = std::size_t(r.owner[p.size() - 1]);
    if (blocked) {
      EXPECT_LE(norm(lone - r.centres[o]), r.radii[o] * (1 + 1e-12));
      EXPECT_LT(norm(r.centres[o] - lone), 1e-12);  // a sphere of its own
      EXPECT_NEAR(r.masses[o], 1e-4, 1e-18);
    } else {
      EXPECT_GT(r.masses[o], 1e-4);  // merged into a sphere of the block's upper group
      EXPECT_GT(r.centres[o].z, 0.0);
    }
    double total = 0.0;
    for (double mm : p.masses) total += mm;  // the context points carry none
    EXPECT_NEAR(std::accumulate(r.masses.begin(), r.masses.end(), 0.0) / total, 1.0, 1e-12);
  }
}

// Incision k of twenty: a vertical blade 4 cm deep from the top face (z from 3 cm down to -1 cm of a block
// 6 cm tall) drawn 5 cm along a direction in the x-y plane, at positions and angles that spread the incisions
// over the block; several cross earlier ones. Partial cuts: the block stays in one piece below them.
SweptSurface incision(int k) {
  const double angle = 2.399963 * k;  // golden angle: directions spread evenly
  const Vec3d dir(std::cos(angle), std::sin(angle), 0.0);
  const Vec3d centre(0.035 * std::sin(1.7 * k + 0.3), 0.028 * std::cos(1.3 * k + 0.1), 0.0);
  std::vector<BladePose> poses;
  for (int s = 0; s <= 4; ++s) {
    const Vec3d c = centre + dir * (-0.025 + 0.0125 * s);
    poses.push_back({Vec3d(c.x, c.y, -0.01), Vec3d(c.x, c.y, 0.031)});
  }
  return sweepSurface(poses);
}

// Fraction of the block's interior samples (4 mm grid) inside a sphere whose centre they see (no cut between:
// the piece's own spheres), and the farthest a sphere reaches out of the block.
void coverage(const MetaballModel& m, const std::vector<SweptSurface>& cuts, const Vec3d& half, double& covered,
              double& protrusion) {
  const double h = 0.004;
  std::vector<Vec3d> samples;
  for (double x = -half.x + 0.5 * h; x < half.x; x += h)
    for (double y = -half.y + 0.5 * h; y < half.y; y += h)
      for (double z = -half.z + 0.5 * h; z < half.z; z += h) samples.emplace_back(x, y, z);
  std::vector<char> in(samples.size(), 0);
  for (std::size_t k = 0; k < samples.size(); ++k)
    for (std::size_t i = 0; i < m.size() && !in[k]; ++i) {
      if (!(norm2(samples[k] - m.rest_centers[i]) < m.rest_radii[i] * m.rest_radii[i])) continue;
      bool hidden = false;
      for (std::size_t c = 0; c < cuts.size() && !hidden; ++c)
        hidden = segmentCrossesSweptSurface(cuts[c], samples[k], m.rest_centers[i]);
      in[k] = !hidden;
    }
  covered = double(std::count(in.begin(), in.end(), 1)) / double(samples.size());
  protrusion = 0.0;
  for (std::size_t i = 0; i < m.size(); ++i)
    for (int a = 0; a < 3; ++a)
      protrusion = std::max(protrusion, std::fabs(m.rest_centers[i][a]) + m.rest_radii[i] - half[a]);
}

// Twenty successive incisions in a 12 x 10 x 6 cm block of 1 cm spheres, each re-packed by Algorithm 1 with the
// earlier cuts respected (the organ's original sphere as the reference mass and 1.5 x its radius as the cap; the
// converted spheres sampled inside the block only, as the dissection model samples inside the organ's surface):
// mass exact (1e-12), no link across any cut, the sphere count bounded (each group keeps at most ceil(its mass /
// the reference mass) spheres; asserted: within 10 % of the original after every cut), and the tissue covered by
// spheres each sample sees at least 0.95 x as well as by the uncut lattice (the packing tests' 95 %) after 1 and
// 10 incisions, 0.9 x after 20 (the cover erodes slowly where incisions cross: docs/cutting.md), with no sphere
// reaching more than 1.5 lattice spacings out of the block (the uncut lattice: 0.25).
TEST(CutRepack, TwentyCutsKeepTheSphereCountBoundedAndTheTissueCovered) {
  MetaballModel m = cuttest::latticeBlock(12, 10, 6);
  const Vec3d half(0.06, 0.05, 0.03);
  const double mass0 = totalMass(m);
  const std::size_t n0 = m.size();
  std::vector<SweptSurface> cuts;
  double cover0 = 0, prot0 = 0;
  coverage(m, cuts, half, cover0, prot0);
  cuts.reserve(20);
  for (int k = 0; k < 20; ++k) {
    cuts.push_back(incision(k));
    const SweptSurface& s = cuts.back();
    CutOptions opt;
    for (int e = 0; e < k; ++e) opt.earlier_cuts.push_back(&cuts[std::size_t(e)]);
    opt.inside = [&](const Vec3d& x) {
      return std::fabs(x.x) < half.x && std::fabs(x.y) < half.y && std::fabs(x.z) < half.z;
    };
    SphereCutResult r = cutSpheres(m, s, opt);
    const std::vector<SweptSurface> earlier(cuts.begin(), cuts.end() - 1);
    RepackOptions ro;
    ro.reference_mass = mass0 / double(n0);  // the organ's original sphere: the budget and the cap do not drift
    ro.max_radius = 1.5 * 0.0075;
    const std::size_t added = repackSpheres(r.spheres, r.points, s, ro, earlier);
    const std::size_t removed = r.cut.size();
    m = std::move(r.spheres);
    EXPECT_NEAR(totalMass(m) / mass0, 1.0, 1e-12) << "cut " << k;
    EXPECT_LT(std::fabs(double(m.size()) - double(n0)), 0.1 * double(n0)) << "cut " << k;
    if (k == 0 || k == 9 || k == 19) {
      double cover = 0, prot = 0;
      coverage(m, cuts, half, cover, prot);
      std::printf(
          "[twenty cuts] after cut %d: %zu spheres (%zu cut, +%zu), coverage %.4f (uncut %.4f), "
          "out of the block by %.2f mm (uncut %.2f mm)\n",
          k + 1, m.size(), removed, added, cover, cover0, prot * 1e3, prot0 * 1e3);
      // Measured (this machine, 2026-11-25): 0.9515, 0.9401, 0.8862 against the uncut 0.9440; out of the block by
      // 8.1, 8.1, 9.4 mm (1.5 x the cap keeps it bounded; the uncut lattice: 2.5 mm).
      EXPECT_GE(cover, (k < 10 ? 0.95 : 0.9) * cover0) << "cut " << k;
      EXPECT_LT(prot, 0.015) << "cut " << k;
    }
  }
  std::size_t crossing = 0;
  for (const auto& e : m.links)
    for (const auto& s : cuts) crossing += segmentCrossesSweptSurface(s, m.rest_centers[e[0]], m.rest_centers[e[1]]);
  EXPECT_EQ(crossing, 0u);
}

}  // namespace
}  // namespace inc
