// Lattice sampling of boxes, ellipsoids and closed meshes: counts, bounds, jitter determinism, mesh volume.
#include <gtest/gtest.h>

#include <cmath>

#include "host/assembly/particle_sampling.h"
#include "model/input_error.h"

using namespace inc;

namespace {

// Closed, outward-oriented axis-aligned box mesh (12 triangles).
TriangleMesh boxMesh(const Vec3d& lo, const Vec3d& hi) {
  TriangleMesh m;
  for (int k = 0; k < 8; ++k)
    m.vertices.push_back(Vec3d(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z));
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// Octahedron |x| + |y| + |z| <= r (volume 4/3 r^3), outward oriented.
TriangleMesh octahedron(double r) {
  TriangleMesh m;
  m.vertices = {{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

}  // namespace

TEST(ParticleSampling, BoxIsACentredLatticeOfCellCentres) {
  const std::vector<Vec3d> p = sampleBox(Vec3d(1, 2, 3), Vec3d(0.1, 0.04, 0.02), LatticeSpec{0.01, 0.0, 1});
  ASSERT_EQ(p.size(), 10u * 4u * 2u);
  Vec3d c;
  for (const auto& x : p) c += x * (1.0 / double(p.size()));
  EXPECT_LT(norm(c - Vec3d(1, 2, 3)), 1e-12);
  EXPECT_NEAR(p.front().x, 1 - 0.045, 1e-12);  // half a cell inside the face
  EXPECT_NEAR(p[1].x - p[0].x, 0.01, 1e-12);   // x fastest
}

TEST(ParticleSampling, JitterIsBoundedAndDeterministic) {
  const LatticeSpec l{0.01, 0.3, 42};
  const std::vector<Vec3d> a = sampleBox(Vec3d(0, 0, 0), Vec3d(0.05, 0.05, 0.05), l);
  const std::vector<Vec3d> b = sampleBox(Vec3d(0, 0, 0), Vec3d(0.05, 0.05, 0.05), l);
  const std::vector<Vec3d> grid = sampleBox(Vec3d(0, 0, 0), Vec3d(0.05, 0.05, 0.05), LatticeSpec{0.01, 0.0, 42});
  const std::vector<Vec3d> other = sampleBox(Vec3d(0, 0, 0), Vec3d(0.05, 0.05, 0.05), LatticeSpec{0.01, 0.3, 43});
  ASSERT_EQ(a.size(), grid.size());
  double moved = 0, differs = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(norm(a[i] - b[i]), 0.0);
    for (int ax = 0; ax < 3; ++ax) EXPECT_LE(std::abs(a[i][ax] - grid[i][ax]), 0.3 * 0.01 + 1e-15);
    moved = std::max(moved, norm(a[i] - grid[i]));
    differs = std::max(differs, norm(a[i] - other[i]));
  }
  EXPECT_GT(moved, 0.1 * 0.01);
  EXPECT_GT(differs, 0.0);  // another seed, another jitter
}

TEST(ParticleSampling, EllipsoidSamplesLieInsideAndFillItsVolume) {
  const Vec3d radii(0.05, 0.03, 0.02);
  const double s = 0.002;
  const std::vector<Vec3d> p = sampleEllipsoid(Vec3d(0.1, 0, 0), radii, LatticeSpec{s, 0.0, 1});
  for (const auto& x : p) {
    const Vec3d d = x - Vec3d(0.1, 0, 0);
    EXPECT_LE((d.x / radii.x) * (d.x / radii.x) + (d.y / radii.y) * (d.y / radii.y) + (d.z / radii.z) * (d.z / radii.z),
              1.0 + 1e-12);
  }
  const double volume = 4.0 / 3.0 * M_PI * radii.x * radii.y * radii.z;
  EXPECT_NEAR(double(p.size()) * s * s * s / volume, 1.0, 0.03);  // lattice count vs volume, 3%
}

TEST(ParticleSampling, MeshSamplingMatchesTheBoxAndTheOctahedronVolume) {
  // A closed box mesh sampled on its own lattice gives exactly the cell centres of the box.
  const double s = 0.01;
  const std::vector<Vec3d> fromMesh =
      sampleMesh(boxMesh(Vec3d(0, 0, 0), Vec3d(0.06, 0.04, 0.03)), LatticeSpec{s, 0.0, 1});
  const std::vector<Vec3d> fromBox =
      sampleBox(Vec3d(0.03, 0.02, 0.015), Vec3d(0.06, 0.04, 0.03), LatticeSpec{s, 0.0, 1});
  ASSERT_EQ(fromMesh.size(), fromBox.size());
  for (std::size_t i = 0; i < fromMesh.size(); ++i) EXPECT_LT(norm(fromMesh[i] - fromBox[i]), 1e-12);
  // Octahedron: count * s^3 approaches its volume; winding number 1 inside, 0 outside.
  const TriangleMesh oct = octahedron(0.05);
  const double so = 0.002;
  const std::vector<Vec3d> p = sampleMesh(oct, LatticeSpec{so, 0.0, 1});
  EXPECT_NEAR(double(p.size()) * so * so * so / (4.0 / 3.0 * 0.05 * 0.05 * 0.05), 1.0, 0.05);
  EXPECT_EQ(meshWindingNumber(oct, Vec3d(0.01, 0.005, -0.003)), 1);
  EXPECT_EQ(meshWindingNumber(oct, Vec3d(0.04, 0.04, 0.0)), 0);
  // Rays through a shared edge or vertex are counted once (the apex column x = y = 0).
  EXPECT_EQ(meshWindingNumber(oct, Vec3d(0.0, 0.0, 0.0)), 1);
  EXPECT_EQ(meshWindingNumber(oct, Vec3d(0.01, 0.0, 0.0)), 1);
}

TEST(ParticleSampling, BadGeometryIsRefusedWithItsKey) {
  auto keyOf = [](const GeometrySpec& g) {
    try {
      sampleGeometry(g, "scene.json");
    } catch (const InputError& e) {
      return e.key();
    }
    return std::string("<no error>");
  };
  GeometrySpec g;
  g.spacing = 0;
  EXPECT_EQ(keyOf(g), "geometry.spacing_m");
  g = GeometrySpec();
  g.jitter = 0.5;
  EXPECT_EQ(keyOf(g), "geometry.jitter");
  g = GeometrySpec();
  g.size.y = -1;
  EXPECT_EQ(keyOf(g), "geometry.size_m");
  g = GeometrySpec();
  g.spacing = 1e-6;  // 0.1 x 0.02 x 0.02 m at 1 um: 4e13 particles
  EXPECT_EQ(keyOf(g), "geometry.size_m");
  g = GeometrySpec();
  g.kind = GeometrySpec::Kind::Sphere;
  g.radius = 0;
  EXPECT_EQ(keyOf(g), "geometry.radius_m");
  g = GeometrySpec();
  g.kind = GeometrySpec::Kind::Mesh;
  EXPECT_EQ(keyOf(g), "geometry.kind");
}
