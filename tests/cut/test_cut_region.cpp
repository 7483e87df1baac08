// NodalRegion: spheres -> MLS points during a stroke: mass, roles, visibility of supports, recomputed moment
// matrices, rigid-motion invariance of the coupling, rest stays at rest.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <set>

#include "cpu_fallback/mls_solver_cpu.h"
#include "cpu_fallback/neighbor_search_cpu.h"
#include "host/cut/cut_nodal_points.h"
#include "host/cut/cut_nodal_region.h"
#include "physics/mls_kernel.h"
#include "tests/support/cut_fixtures.h"
#include "tests/support/mls_test_scenes.h"

namespace inc {
namespace {

NodalRegionSettings settings() {
  NodalRegionSettings s;
  s.samples_per_diameter = 4;
  s.backend = BackendKind::Cpu;
  s.precision = Precision::Float64;
  s.mls.source = "<test region>";
  s.mls.material.youngs_modulus_pa = 5.0e3;
  s.mls.material.poisson_ratio = 0.45;
  s.mls.material.density_kg_m3 = 1000.0;
  s.mls.material.damping_per_s = 1.0;
  s.mls.gravity = Vec3d(0, 0, 0);
  return s;
}

// A blade along y swept along x over [-0.1, x1] at height z = 0 (between two sphere layers of the block).
SweptSurface stroke(double x1) { return cuttest::straightSweep(-0.1, x1, -0.1, 0.1); }

ConvertedSphereState atRest(const MetaballModel& m, std::int32_t b) {
  ConvertedSphereState s;
  s.position = m.rest_centers[std::size_t(b)];
  return s;
}

const cpu::MlsCpuSolver<double>& cpuSolver(const NodalRegion& r) {
  return dynamic_cast<const cpu::MlsCpuSolver<double>&>(*r.solver());
}

// Mass: the spheres still in PBD (role Pbd) plus all points equal the base (interface spheres are counted by
// their points, 1e-12). Roles: interface spheres are exactly the PBD-role link neighbours of cut spheres.
TEST(CutRegion, ConversionConservesMassAndMarksTheInterface) {
  const MetaballModel m = cuttest::latticeBlock(8, 4, 4);
  const SweptSurface s = stroke(0.0);
  NodalRegion region(m, settings(), {});
  const auto cut = findCutSpheres(s, m.rest_centers, m.rest_radii);
  ASSERT_FALSE(cut.empty());
  region.convert(
      cut, [&](std::int32_t b) { return atRest(m, b); }, s);
  double pbd = 0.0;
  std::set<std::int32_t> expected_interface;
  for (auto b : cut)
    for (const auto& l : m.links) {
      const std::int32_t o = l[0] == b ? l[1] : (l[1] == b ? l[0] : -1);
      if (o >= 0 && std::find(cut.begin(), cut.end(), o) == cut.end()) expected_interface.insert(o);
    }
  for (std::size_t b = 0; b < m.size(); ++b) {
    const SphereRole role = region.role(std::int32_t(b));
    if (role == SphereRole::Pbd) pbd += m.masses[b];
    EXPECT_EQ(role == SphereRole::Interface, expected_interface.count(std::int32_t(b)) == 1) << b;
    EXPECT_EQ(role == SphereRole::Cut, std::find(cut.begin(), cut.end(), std::int32_t(b)) != cut.end()) << b;
  }
  EXPECT_EQ(region.interfaceCount(), expected_interface.size());
  // One shared lattice: every point inside its sphere's ball, no two points in one place, every sphere sampled.
  const auto& x = region.restPoints();
  std::set<std::array<long long, 3>> seen;
  std::set<std::int32_t> sampled;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const std::int32_t b = region.pointSphere()[i];
    EXPECT_LT(norm(x[i] - m.rest_centers[std::size_t(b)]), m.rest_radii[std::size_t(b)]) << i;
    EXPECT_TRUE(
        seen.insert({std::llround(x[i].x * 1e7), std::llround(x[i].y * 1e7), std::llround(x[i].z * 1e7)}).second)
        << i;
    sampled.insert(b);
  }
  EXPECT_EQ(sampled.size(), cut.size() + expected_interface.size());
  EXPECT_NEAR((pbd + region.pointMass()) / totalMass(m), 1.0, 1e-12);
}

// No support crosses the stroke; the lists are symmetric; every point that lost a neighbour to the cut has its
// moment matrix recomputed from the remaining ones (equal to A_i^-1 of its filtered list to 1e-9, and unlike
// the uncut one by more than 1 %). Extending the stroke by a strip drops more pairs and recomputes again.
TEST(CutRegion, SupportsNeverCrossTheCutAndMomentMatricesAreRecomputed) {
  const MetaballModel m = cuttest::latticeBlock(8, 4, 4);
  SweptSurface s = stroke(-0.01);
  NodalRegion region(m, settings(), {});
  region.convert(
      findCutSpheres(s, m.rest_centers, m.rest_radii), [&](std::int32_t b) { return atRest(m, b); }, s);
  const auto& x = region.restPoints();
  const NeighborLists& l = region.supports();
  const double h = 2.0 * region.pointSpacing();
  const NeighborLists all = cpu::GridNeighborSearch<double>(x, h).querySelf(h);
  std::set<std::pair<int, int>> pairs;
  for (std::size_t q = 0; q < l.queryCount(); ++q)
    for (auto k = l.offsets[q]; k < l.offsets[q + 1]; ++k) {
      ASSERT_FALSE(segmentCrossesSweptSurface(s, x[q], x[std::size_t(l.indices[std::size_t(k)])]));
      pairs.insert({int(q), l.indices[std::size_t(k)]});
    }
  for (const auto& p : pairs) ASSERT_TRUE(pairs.count({p.second, p.first})) << "asymmetric pair";
  EXPECT_GT(region.supportsRemoved(), 0u);
  EXPECT_EQ(pairs.size() + region.supportsRemoved(), all.indices.size());

  const auto momentInverse = [&](const NeighborLists& lists, std::size_t i) {
    const auto& model = cpuSolver(region).model();
    const Vec3d xi = x[i];
    Mat3d a;
    int count = 0;
    for (auto k = lists.offsets[i]; k < lists.offsets[i + 1]; ++k) {
      const Vec3d xij = x[std::size_t(lists.indices[std::size_t(k)])] - xi;
      const double w = mlsKernelWeight(norm2(xij), double(model.support));
      count += w > 0;
      accumulateMomentMatrix(a, xij, w);
    }
    return regularisedMomentInverse(a, count, 1.0e6).inverse;
  };
  // Points whose list changed: A_i^-1 equals the one of the filtered list; most differ from the uncut one by
  // more than 1 % for at least a third of them (a pair dropped near h has almost no weight).
  const auto checkRecomputed = [&](const NeighborLists& lists, const NeighborLists& before, int& affected,
                                   int& changed) {
    const auto& model = cpuSolver(region).model();
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (lists.count(i) == before.count(i)) continue;
      ++affected;
      const Mat3d now = model.moment_inverse[i], fresh = momentInverse(lists, i), old = momentInverse(before, i);
      ASSERT_LT(frobeniusNorm(now - fresh), 1e-9 * frobeniusNorm(fresh)) << i;
      changed += frobeniusNorm(now - old) > 1e-2 * frobeniusNorm(old);
    }
  };
  int affected = 0, changed = 0;
  checkRecomputed(l, all, affected, changed);
  EXPECT_GT(affected, 0);
  EXPECT_GE(3 * changed, affected);
  // The stroke goes on by one strip inside the converted layer (x -0.01 -> -0.005): more pairs drop.
  const NeighborLists before = region.supports();
  SweptSurface fresh = cuttest::straightSweep(-0.01, -0.005, -0.1, 0.1, 1);
  const std::size_t dropped = region.cutSupports(fresh);
  EXPECT_GT(dropped, 0u);
  affected = changed = 0;
  checkRecomputed(region.supports(), before, affected, changed);
  EXPECT_GT(affected, 0);
  EXPECT_GE(3 * changed, affected);
}

// Converted from a rigidly rotated and translated state, the points carry the rigid motion: no strain energy.
// The rotation-aware eq. 13 (physics/cut_coupling.h) puts every interface sphere whose points span a volume at
// R C + t (1e-12 m); a group of too few or collinear points follows the plain mean, off by (R - I)(mean X - C)
// (checked to 1e-12). Then the springs are at rest and nothing moves (1e-12 m over 4 ms), rotated or not.
TEST(CutRegion, RigidMotionMakesNoStrainAndNoMotion) {
  const MetaballModel m = cuttest::latticeBlock(6, 4, 4);
  const SweptSurface s = stroke(0.0);
  for (int rotated = 1; rotated >= 0; --rotated) {
    const Mat3d R = rotated ? mls_test::rotation(Vec3d(0.3, -1.0, 0.5), 0.7) : Mat3d::identity();
    const Vec3d t(0.02, -0.01, 0.03);
    NodalRegion region(m, settings(), {});
    region.convert(
        findCutSpheres(s, m.rest_centers, m.rest_radii),
        [&](std::int32_t b) {
          ConvertedSphereState st;
          st.position = R * m.rest_centers[std::size_t(b)] + t;
          st.rotation = R;
          return st;
        },
        s);
    EXPECT_LT(region.lastReduction().elastic_energy, 1e-20);
    std::vector<std::int32_t> ids;
    std::vector<Vec3d> pos;
    region.interfacePositions(ids, pos);
    ASSERT_FALSE(ids.empty());
    int rotating = 0;
    for (std::size_t k = 0; k < ids.size(); ++k) {
      MlsCouplingGroups g;
      Vec3d mean;
      for (std::size_t i = 0; i < region.pointCount(); ++i)
        if (region.pointSphere()[i] == ids[k]) {
          mean += region.restPoints()[i];
          g.members.push_back(std::int32_t(i));
        }
      mean *= 1.0 / double(g.members.size());
      const Vec3d c = m.rest_centers[std::size_t(ids[k])];
      g.member_offsets = {0, std::int32_t(g.members.size())};
      g.rest_centres = {c};
      g.spring_offsets = {0, 0};
      const bool rotates = mlsCouplingFrames(g, region.restPoints()).min_inertia[0] > 0.0;
      rotating += rotates;
      const Vec3d expected = rotates ? R * c + t : R * c + t + (R - Mat3d::identity()) * (mean - c);
      EXPECT_LT(norm(pos[k] - expected), 1e-12) << "interface sphere " << ids[k] << (rotates ? " (rotating)" : "");
    }
    std::printf("%s: %d of %zu interface spheres rotate\n", rotated ? "rotated" : "translated", rotating, ids.size());
    EXPECT_GE(4 * rotating, 3 * int(ids.size()));          // most interface spheres hold a volume of points
    if (rotated && rotating != int(ids.size())) continue;  // a non-rotating group's springs would pull
    std::vector<Vec3d> u0;
    region.solver()->displacements(u0);
    region.advance(0.004, 0, [&](std::int32_t j) { return R * m.rest_centers[std::size_t(j)] + t; });
    EXPECT_LT(region.springEnergy(), 1e-24);
    std::vector<Vec3d> u1;
    region.solver()->displacements(u1);
    double moved = 0.0;
    for (std::size_t i = 0; i < u0.size(); ++i) moved = std::max(moved, norm(u1[i] - u0[i]));
    EXPECT_LT(moved, 1e-12);
  }
}

}  // namespace
}  // namespace inc
