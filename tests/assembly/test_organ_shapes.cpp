// Tests for the procedural organ shapes: closed, manifold, outward, embedded, sized as asked, volumes vs analytic.
#include <gtest/gtest.h>

#include <cmath>

#include "host/assembly/organ_shapes.h"
#include "host/io/mesh_self_intersection.h"
#include "model/input_error.h"

namespace inc {
namespace {

constexpr double kPi = 3.14159265358979323846;

void expectWatertight(const TriangleMesh& m) {
  const MeshReport r = analyzeMesh(m);
  EXPECT_EQ(r.boundary_edges, 0);
  EXPECT_EQ(r.non_manifold_edges, 0);
  EXPECT_EQ(r.inconsistent_edges, 0);
  EXPECT_EQ(r.degenerate_triangles, 0);
  EXPECT_EQ(r.components, 1);
  EXPECT_TRUE(r.watertight());
  EXPECT_GT(r.signed_volume, 0.0) << "outward orientation";
  // Euler characteristic: V - E + F with E = 3F/2.
  EXPECT_EQ(r.vertex_count - 3 * r.triangle_count / 2 + r.triangle_count, 2) << "a sphere-topology surface";
}

TEST(OrganShapes, GeodesicSphereCountsAndVolume) {
  const TriangleMesh m = makeSphereMesh(0.05, 10);
  EXPECT_EQ(m.vertices.size(), 10u * 100u + 2u);
  EXPECT_EQ(m.triangles.size(), 20u * 100u);
  expectWatertight(m);
  for (const auto& v : m.vertices) EXPECT_NEAR(norm(v), 0.05, 1e-15);
  const double exact = 4.0 / 3.0 * kPi * 0.05 * 0.05 * 0.05;
  const double v = analyzeMesh(m).signed_volume;
  EXPECT_LT(v, exact);  // inscribed polyhedron
  EXPECT_NEAR(v, exact, 0.01 * exact);
}

TEST(OrganShapes, BoxIsExact) {
  const TriangleMesh m = makeBoxMesh({0.1, 0.2, 0.3}, 3, Vec3d{1.0, 2.0, 3.0});
  expectWatertight(m);
  EXPECT_NEAR(analyzeMesh(m).signed_volume, 0.2 * 0.4 * 0.6, 1e-14);
}

TEST(OrganShapes, TorusVolumeAndGenus) {
  const TriangleMesh m = makeTorusMesh(0.04, 0.01, 64, 24);
  const MeshReport r = analyzeMesh(m);
  EXPECT_TRUE(r.watertight());
  EXPECT_EQ(r.vertex_count - 3 * r.triangle_count / 2 + r.triangle_count, 0) << "genus 1";
  const double exact = 2.0 * kPi * kPi * 0.04 * 0.01 * 0.01;
  EXPECT_NEAR(r.signed_volume, exact, 0.02 * exact);
}

TEST(OrganShapes, LiverLikeIsClosedEmbeddedAndLiverSized) {
  const TriangleMesh m = makeLiverLikeMesh();
  EXPECT_NEAR(double(m.vertices.size()), 8000.0, 400.0);
  expectWatertight(m);
  EXPECT_TRUE(findSelfIntersections(m, 1).empty()) << "embedded surface";
  const MeshReport r = analyzeMesh(m);
  EXPECT_NEAR(r.bbox_max.x - r.bbox_min.x, 0.20, 1e-12);
  // Thinner than wide and tall: a flattened organ, volume of an adult liver's order (1-2 L).
  EXPECT_LT(r.bbox_max.y - r.bbox_min.y, 0.8 * (r.bbox_max.x - r.bbox_min.x));
  EXPECT_GT(r.signed_volume, 0.5e-3);
  EXPECT_LT(r.signed_volume, 3.0e-3);
  // Variants differ but stay valid.
  const TriangleMesh v = makeLiverLikeMesh({2000, 0.15, 3});
  expectWatertight(v);
  EXPECT_TRUE(findSelfIntersections(v, 1).empty());
}

TEST(OrganShapes, ByNameAndBadInput) {
  for (const char* name : {"sphere", "box", "torus", "liver"}) {
    const TriangleMesh m = makeOrganShape(name, 0.1, 1000);
    const MeshReport r = analyzeMesh(m);
    EXPECT_TRUE(r.watertight()) << name;
    const Vec3d e = r.bbox_max - r.bbox_min;
    EXPECT_NEAR(std::max({e.x, e.y, e.z}), 0.1, 2e-3) << name;
  }
  EXPECT_THROW(makeOrganShape("kidney", 0.1, 1000), InputError);
  EXPECT_THROW(makeOrganShape("sphere", -1.0, 1000), InputError);
  EXPECT_THROW(makeOrganShape("sphere", 0.1, 3), InputError);
}

}  // namespace
}  // namespace inc
