// connectSphereGraph: stragglers linked inside the mesh, never through the air, dropped with their mass kept, and
// separate mesh pieces kept apart.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "host/assembly/organ_shapes.h"
#include "host/assembly/sphere_graph_repair.h"

namespace inc {
namespace {

constexpr double kPi = 3.14159265358979323846;

void addSphere(MetaballModel& mb, const Vec3d& c, double r, double mass) {
  mb.rest_centers.push_back(c);
  mb.rest_radii.push_back(r);
  mb.masses.push_back(mass);
}

void link(MetaballModel& mb, int i, int j) {
  mb.links.push_back({i, j});
  mb.link_rest_lengths.push_back(norm(mb.rest_centers[std::size_t(i)] - mb.rest_centers[std::size_t(j)]));
}

std::vector<int> degrees(const MetaballModel& mb) {
  std::vector<int> d(mb.size(), 0);
  for (const auto& l : mb.links) {
    ++d[std::size_t(l[0])];
    ++d[std::size_t(l[1])];
  }
  return d;
}

double totalMass(const MetaballModel& mb) {
  double m = 0;
  for (double x : mb.masses) m += x;
  return m;
}

Vec3d onRing(double major, double degrees) {
  const double a = degrees * kPi / 180.0;
  return {major * std::cos(a), major * std::sin(a), 0.0};
}

}  // namespace

// Spheres along a torus tube (major radius 3 cm, tube 1 cm): a linked arc from 0 to 40 degrees, a lone sphere at 58
// degrees (its chord to the arc runs inside the tube) and one at 180 degrees (its nearest spheres lie across the
// hole). The first is linked, the second dropped with its mass handed on.
TEST(SphereGraphRepair, LinksInsideTheMeshAndDropsAcrossTheAir) {
  const TriangleMesh torus = makeTorusMesh(0.03, 0.01, 64, 24);
  MetaballModel mb;
  for (int k = 0; k <= 4; ++k) addSphere(mb, onRing(0.03, 10.0 * k), 0.004, 1.0e-3);
  for (int k = 0; k < 4; ++k) link(mb, k, k + 1);
  addSphere(mb, onRing(0.03, 58.0), 0.004, 1.0e-3);   // 5: gap to sphere 4 about 1.4 mm
  addSphere(mb, onRing(0.03, 180.0), 0.004, 2.0e-3);  // 6: 6 cm across the hole from sphere 0
  const double mass = totalMass(mb);
  const SphereGraphRepair r = connectSphereGraph(mb, torus, 0.1);  // a reach past the hole: the air must refuse it
  EXPECT_EQ(r.components_before, 3);
  EXPECT_EQ(r.stragglers, 2);
  EXPECT_EQ(r.linked, 1);
  EXPECT_EQ(r.dropped, 1);
  EXPECT_NEAR(r.dropped_mass, 2.0e-3, 1e-15);
  ASSERT_EQ(mb.size(), 6u);
  EXPECT_NEAR(totalMass(mb), mass, 1e-15);
  EXPECT_NEAR(mb.masses[5], 3.0e-3, 1e-15);  // the nearest kept sphere (at 58 degrees) took the dropped one's mass
  EXPECT_EQ(r.components_after, 1);
  EXPECT_EQ(sphereGraphComponents(mb), 1);
  for (int d : degrees(mb)) EXPECT_GT(d, 0);
  for (std::size_t l = 0; l + 1 < mb.links.size(); ++l) EXPECT_LT(mb.links[l], mb.links[l + 1]);
  for (std::size_t l = 0; l < mb.links.size(); ++l) {
    EXPECT_LT(mb.links[l][0], mb.links[l][1]);
    EXPECT_NEAR(mb.link_rest_lengths[l],
                norm(mb.rest_centers[std::size_t(mb.links[l][0])] - mb.rest_centers[std::size_t(mb.links[l][1])]),
                1e-15);
  }
}

// Two balls 4 mm apart are two pieces: their spheres stay two groups however near, and nothing is dropped.
TEST(SphereGraphRepair, SeparateMeshPiecesStaySeparate) {
  TriangleMesh two = makeSphereMesh(0.01, 4, Vec3d(-0.012, 0, 0));
  const TriangleMesh right = makeSphereMesh(0.01, 4, Vec3d(0.012, 0, 0));
  const int offset = int(two.vertices.size());
  two.vertices.insert(two.vertices.end(), right.vertices.begin(), right.vertices.end());
  for (auto t : right.triangles) two.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  MetaballModel mb;
  addSphere(mb, Vec3d(-0.012, 0, 0), 0.005, 1e-3);
  addSphere(mb, Vec3d(-0.005, 0, 0), 0.003, 1e-3);
  link(mb, 0, 1);
  addSphere(mb, Vec3d(0.005, 0, 0), 0.003, 1e-3);
  addSphere(mb, Vec3d(0.012, 0, 0), 0.005, 1e-3);
  link(mb, 2, 3);
  const SphereGraphRepair r = connectSphereGraph(mb, two, 0.05);
  EXPECT_EQ(r.mesh_pieces, 2);
  EXPECT_EQ(r.stragglers, 0);
  EXPECT_FALSE(r.changed());
  EXPECT_EQ(mb.links.size(), 2u);
  EXPECT_EQ(r.components_after, 2);
}

// An empty surface stands for a convex body: a straggler within reach is linked to up to three nearest spheres.
TEST(SphereGraphRepair, ConvexBodyLinksAStragglerToThreeNeighbours) {
  MetaballModel mb;
  addSphere(mb, Vec3d(0, 0, 0), 0.004, 1e-3);
  addSphere(mb, Vec3d(0.006, 0, 0), 0.004, 1e-3);
  addSphere(mb, Vec3d(0, 0.006, 0), 0.004, 1e-3);
  addSphere(mb, Vec3d(0.006, 0.006, 0), 0.004, 1e-3);
  link(mb, 0, 1);
  link(mb, 0, 2);
  link(mb, 1, 3);
  link(mb, 2, 3);
  addSphere(mb, Vec3d(0.003, 0.003, 0.012), 0.004, 1e-3);  // gap to the square's spheres about 4.7 mm
  MetaballModel far = mb;
  const SphereGraphRepair r = connectSphereGraph(mb, TriangleMesh{}, 0.006);
  EXPECT_EQ(r.linked, 1);
  EXPECT_EQ(r.links_added, 3);
  EXPECT_EQ(degrees(mb)[4], 3);
  EXPECT_EQ(r.components_after, 1);
  // Out of reach, it is dropped.
  const SphereGraphRepair f = connectSphereGraph(far, TriangleMesh{}, 0.003);
  EXPECT_EQ(f.dropped, 1);
  EXPECT_EQ(far.size(), 4u);
  EXPECT_NEAR(totalMass(far), 5e-3, 1e-15);
}

}  // namespace inc
