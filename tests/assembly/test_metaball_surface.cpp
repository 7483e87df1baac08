// The metaball organ's skinned surface and its packed sphere fill (pbd.target_spheres).
#include <gtest/gtest.h>

#include <cmath>

#include "host/assembly/scene_surface.h"
#include "host/scene/scene_compile.h"
#include "host/sim/metaball_simulation.h"
#include "model/input_error.h"

using namespace inc;

namespace {

// An 8 x 6 x 4 cm ellipsoid on 1 cm spheres, under gravity, clamped at its bottom cap.
Scene ellipsoidScene(int target_spheres) {
  Scene s;
  s.file = "<test>";
  s.geometry.kind = GeometrySpec::Kind::Ellipsoid;
  s.geometry.radii = Vec3d(0.04, 0.03, 0.02);
  s.geometry.spacing = 0.01;
  s.material.youngs_modulus_pa = 5.0e3;
  s.material.damping_per_s = 4.0;
  s.models.pbd_metaballs = true;
  s.pbd.solver = "gauss_seidel";
  s.pbd.target_spheres = target_spheres;
  // The bottom 8 mm is clamped (lattice: the lowest layer of centres). A coarse packing's lowest centres sit
  // higher (120 spheres: 8.5 mm above the bottom), so its clamp reaches 14 mm up; a box that holds no centre
  // is refused (it would let the organ fall).
  FixedRegion fx;
  fx.min = Vec3d(-1, -1, -1);
  fx.max = Vec3d(1, 1, target_spheres > 0 ? -0.006 : -0.012);
  s.fixed.push_back(fx);
  return s;
}

double maxVertexDistance(const TriangleMesh& a, const TriangleMesh& b) {
  double d = 0;
  for (std::size_t i = 0; i < a.vertices.size(); ++i) d = std::max(d, norm(a.vertices[i] - b.vertices[i]));
  return d;
}

}  // namespace

// At rest the skin reproduces the rest surface exactly (weights partition unity, rotations identity).
TEST(MetaballSurface, AtRestTheSkinIsTheRestSurface) {
  const Scene s = ellipsoidScene(0);
  auto m = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  TriangleMesh skin;
  ASSERT_TRUE(m->currentSurface(skin));
  const TriangleMesh rest = sceneSurfaceMesh(compileScene(s));
  ASSERT_EQ(skin.vertices.size(), rest.vertices.size());
  EXPECT_EQ(skin.triangles, rest.triangles);
  EXPECT_LT(maxVertexDistance(skin, rest), 1e-12);  // m
}

// Under gravity the skin sags with the spheres: it stays closed, no vertex moves farther than the farthest
// sphere (a convex blend of sphere motions, up to the rotation term: 20 % slack), and it does move.
TEST(MetaballSurface, SkinFollowsTheSpheresAndStaysClosed) {
  const Scene s = ellipsoidScene(0);
  auto m = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  FrameReport rep;
  for (int f = 0; f < 20; ++f) rep = m->advance(1.0 / 60.0);
  ASSERT_TRUE(rep.finite);
  TriangleMesh skin;
  ASSERT_TRUE(m->currentSurface(skin));
  const MeshReport r = analyzeMesh(skin);
  EXPECT_TRUE(r.closed());
  EXPECT_EQ(r.inconsistent_edges, 0);
  const double moved = maxVertexDistance(skin, sceneSurfaceMesh(compileScene(s)));
  EXPECT_GT(moved, 1e-4);  // it sags visibly (> 0.1 mm)
  EXPECT_LT(moved, 1.2 * rep.max_displacement + 1e-9);
}

// With pbd.target_spheres the packer fills the surface: about that many spheres, total mass = density x
// enclosed volume of the surface mesh within 3 %, every centre inside the ellipsoid.
TEST(MetaballSurface, TargetSpheresUsesThePacker) {
  const Scene s = ellipsoidScene(120);
  const MetaballModel mb = buildSceneMetaballs(compileScene(s));
  EXPECT_GT(int(mb.size()), 60);
  EXPECT_LE(int(mb.size()), 120);
  double mass = 0;
  for (double mi : mb.masses) mass += mi;
  const double volume = analyzeMesh(sceneSurfaceMesh(compileScene(s))).signed_volume;
  EXPECT_NEAR(mass, s.material.density_kg_m3 * volume, 0.03 * s.material.density_kg_m3 * volume);
  for (const Vec3d& c : mb.rest_centers) {
    const double q = c.x * c.x / (0.04 * 0.04) + c.y * c.y / (0.03 * 0.03) + c.z * c.z / (0.02 * 0.02);
    EXPECT_LT(q, 1.0);
  }
  auto m = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  EXPECT_EQ(m->particleCount(), mb.size());
}
