// Sphere-graph connectivity of the scene's fills (lattice and packer) on thin parts: no sphere without a link, one
// component per mesh piece; and the Armadillo (../shared/organs) filled and settled without losing volume.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "host/assembly/metaball_packing.h"
#include "host/assembly/particle_sampling.h"
#include "host/io/mesh.h"
#include "host/scene/scene_compile.h"
#include "host/sim/metaball_simulation.h"
#include "model/input_error.h"
#include "tests/support/repo_paths.h"
#include "tests/support/temp_dir.h"

using namespace inc;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A dumbbell revolved about `axis` (by default the lattice diagonal (1, 1, 1)): two balls of radius `bulb` joined by a
// neck of radius `neck`, `length` from pole to pole, centred at the origin. A neck thinner than the lattice spacing
// holds a chain of cells that meet only at their corners, which overlap nothing at radius 0.75 spacing.
TriangleMesh makeDumbbell(double bulb, double neck, double length, Vec3d axis = Vec3d(1, 1, 1), int rings = 96,
                          int segments = 24) {
  axis *= 1.0 / norm(axis);
  Vec3d u = cross(axis, std::fabs(axis.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0));
  u *= 1.0 / norm(u);
  const Vec3d v = cross(axis, u);
  const double half = 0.5 * length, centre = half - bulb;
  TriangleMesh m;
  m.vertices.push_back(axis * -half);  // pole 0
  for (int k = 1; k < rings; ++k) {
    const double t = -half + length * k / rings;
    const double d = std::fabs(t) - centre;
    const double r = std::max(neck, std::sqrt(std::max(0.0, bulb * bulb - d * d)));
    for (int j = 0; j < segments; ++j) {
      const double a = 2.0 * kPi * j / segments;
      m.vertices.push_back(axis * t + u * (r * std::cos(a)) + v * (r * std::sin(a)));
    }
  }
  m.vertices.push_back(axis * half);  // pole 1
  const int top = int(m.vertices.size()) - 1;
  const auto at = [&](int ring, int j) { return 1 + (ring - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) {
    m.triangles.push_back({0, at(1, j + 1), at(1, j)});
    for (int k = 1; k + 1 < rings; ++k) {
      m.triangles.push_back({at(k, j), at(k, j + 1), at(k + 1, j + 1)});
      m.triangles.push_back({at(k, j), at(k + 1, j + 1), at(k + 1, j)});
    }
    m.triangles.push_back({top, at(rings - 1, j), at(rings - 1, j + 1)});
  }
  requireClosedMesh(m, "dumbbell", "mesh");  // flips it outward if the winding came out inward
  return m;
}

// A PBD metaball scene filling the mesh file `path` (already in metres).
Scene meshScene(const std::string& path, double scale, double spacing, int target_spheres) {
  Scene s;
  s.file = "<test>";
  s.name = "connectivity";
  s.geometry.kind = GeometrySpec::Kind::Mesh;
  s.geometry.mesh_path = path;
  s.geometry.mesh_scale = scale;
  s.geometry.spacing = spacing;
  s.material.youngs_modulus_pa = 5.0e3;
  s.material.damping_per_s = 4.0;
  s.models.pbd_metaballs = true;
  s.pbd.target_spheres = target_spheres;
  return s;
}

std::vector<int> linkDegrees(const MetaballModel& mb) {
  std::vector<int> degree(mb.size(), 0);
  for (const auto& l : mb.links) {
    ++degree[std::size_t(l[0])];
    ++degree[std::size_t(l[1])];
  }
  return degree;
}

int spheresWithoutLink(const MetaballModel& mb) {
  int n = 0;
  for (int d : linkDegrees(mb)) n += d == 0;
  return n;
}

double totalMass(const MetaballModel& mb) {
  double m = 0;
  for (double x : mb.masses) m += x;
  return m;
}

double signedVolume(const TriangleMesh& m) {
  double v = 0;
  for (const auto& t : m.triangles)
    v += dot(m.vertices[std::size_t(t[0])], cross(m.vertices[std::size_t(t[1])], m.vertices[std::size_t(t[2])]));
  return v / 6.0;
}

Vec3d triangleNormal(const TriangleMesh& m, const std::array<int, 3>& t) {
  const Vec3d n = cross(m.vertices[std::size_t(t[1])] - m.vertices[std::size_t(t[0])],
                        m.vertices[std::size_t(t[2])] - m.vertices[std::size_t(t[0])]);
  const double l = norm(n);
  return l > 0 ? n * (1.0 / l) : n;
}

// Edges whose two triangles face apart at rest (normals at less than 90 degrees) and fold over each other now
// (more than 90 degrees): a skin turning inside out folds there, whatever the body's overall rotation.
int foldedEdges(const TriangleMesh& rest, const TriangleMesh& now) {
  std::map<std::pair<int, int>, std::vector<int>> faces_of_edge;
  for (std::size_t t = 0; t < rest.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      const int a = rest.triangles[t][std::size_t(c)], b = rest.triangles[t][std::size_t((c + 1) % 3)];
      faces_of_edge[{std::min(a, b), std::max(a, b)}].push_back(int(t));
    }
  int folded = 0;
  for (const auto& [edge, faces] : faces_of_edge) {
    if (faces.size() != 2) continue;
    const auto& t0 = rest.triangles[std::size_t(faces[0])];
    const auto& t1 = rest.triangles[std::size_t(faces[1])];
    if (dot(triangleNormal(rest, t0), triangleNormal(rest, t1)) > 0 &&
        dot(triangleNormal(now, t0), triangleNormal(now, t1)) < 0)
      ++folded;
  }
  return folded;
}

std::string armadilloPath() { return test::sharedPath("organs/Armadillo_verysimplified.obj"); }

// The Armadillo (about 13 x 15 x 11.5 file units, 229.6 units^3) at 4.944 mm per unit: 6 x 7.5 x 5.7 cm, 27.75 cm^3.
constexpr double kArmadilloScale = 0.004944;

}  // namespace

// The dumbbell's neck (radius half a spacing, along the lattice diagonal) holds cells that overlap none of their
// neighbours: before the fix they were spheres without a constraint and the fill fell apart in pieces.
TEST(SphereConnectivity, LatticeFillOfAThinDiagonalNeckIsOneLinkedGraph) {
  const double spacing = 0.005;
  const TriangleMesh dumbbell = makeDumbbell(0.015, 0.5 * spacing, 0.12);
  const test::TempDir dir("connect_lattice");
  const std::string path = (std::filesystem::path(dir.str()) / "dumbbell.obj").string();
  writeObj(path, dumbbell);
  const Scene s = meshScene(path, 1.0, spacing, 0);
  std::string note;
  const MetaballModel mb = buildSceneMetaballs(compileScene(s), &note);
  const std::size_t cells = sampleMesh(dumbbell, LatticeSpec{spacing, 0.0, 1}).size();
  EXPECT_EQ(spheresWithoutLink(mb), 0) << note;
  EXPECT_EQ(sphereGraphComponents(mb), 1) << note;
  // Every lattice cell's mass is in the model, whether its sphere was linked or dropped.
  EXPECT_NEAR(totalMass(mb), double(cells) * s.material.density_kg_m3 * spacing * spacing * spacing,
              1e-9 * totalMass(mb));
  EXPECT_NE(note.find("lattice: "), std::string::npos) << note;
  EXPECT_NE(note.find("1 component for 1 mesh piece"), std::string::npos) << note;
}

// A neck thinner than the lattice along x holds no cell at all: the two bulbs' groups lie 64 mm apart, far beyond
// any link, and dropping one would lose half the body. The scene is refused under the key that sets the lattice.
TEST(SphereConnectivity, LatticeThatCannotJoinItsPartsIsRefusedNamingTheSpacing) {
  const TriangleMesh dumbbell = makeDumbbell(0.014, 0.0015, 0.12, Vec3d(1, 0, 0));
  const test::TempDir dir("connect_refused");
  const std::string path = (std::filesystem::path(dir.str()) / "dumbbell.obj").string();
  writeObj(path, dumbbell);
  try {
    const MetaballModel mb = buildSceneMetaballs(compileScene(meshScene(path, 1.0, 0.005, 0)));
    ADD_FAILURE() << "accepted: " << mb.size() << " spheres in " << sphereGraphComponents(mb) << " components";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "geometry.spacing_m") << e.what();
    EXPECT_NE(e.reason().find("too thin"), std::string::npos) << e.what();
  }
}

// The packer on the same thin neck: every sphere linked, one component.
TEST(SphereConnectivity, PackedThinDiagonalNeckIsOneLinkedGraph) {
  const TriangleMesh dumbbell = makeDumbbell(0.015, 0.0025, 0.12);
  PackingOptions o;
  o.target_spheres = 150;
  o.samples = 8000;
  const PackedOrgan p = packOrgan(dumbbell, o);
  EXPECT_EQ(spheresWithoutLink(p.model), 0) << describePack(p.report);
  EXPECT_EQ(sphereGraphComponents(p.model), 1) << describePack(p.report);
  EXPECT_EQ(p.report.components, 1);
}

// The Armadillo's thin limbs: at 4.8 mm spacing its lattice fill left three spheres without any constraint.
TEST(SphereConnectivity, ArmadilloLatticeFillHasNoStraggler) {
  if (!std::filesystem::exists(armadilloPath())) GTEST_SKIP() << "shared organ mesh absent: " << armadilloPath();
  const Scene s = meshScene(armadilloPath(), kArmadilloScale, 0.0048, 0);
  std::string note;
  const MetaballModel mb = buildSceneMetaballs(compileScene(s), &note);
  EXPECT_EQ(spheresWithoutLink(mb), 0) << note;
  EXPECT_EQ(sphereGraphComponents(mb), 1) << note;
  std::printf("armadillo lattice: %s\n", note.c_str());
}

TEST(SphereConnectivity, ArmadilloPackedFillHasNoStraggler) {
  if (!std::filesystem::exists(armadilloPath())) GTEST_SKIP() << "shared organ mesh absent: " << armadilloPath();
  const Scene s = meshScene(armadilloPath(), kArmadilloScale, 0.005, 600);
  std::string note;
  const MetaballModel mb = buildSceneMetaballs(compileScene(s), &note);
  EXPECT_EQ(spheresWithoutLink(mb), 0) << note;
  EXPECT_EQ(sphereGraphComponents(mb), 1) << note;
  std::printf("armadillo packed: %s\n", note.c_str());
}

namespace {

// The Armadillo standing on its feet (held below 19 mm under its centre), gravity along -y, settled for 1 s (the
// lattice at 4.8 mm, where it had stragglers): no sphere falls away, the skinned surface keeps its volume within 8%
// (measured: +5.9% lattice, +3.4% packed; before the fix the lattice's stragglers fell 1.9 m and stretched it by 50%)
// and does not turn inside out. At these defaults (XPBD, 10 Jacobi iterations, 4 substeps) the thin legs give way and
// the body tips over and hangs from its feet: PBD's stiffness here is set by the iterations more than by E (at 1 MPa it
// tips the same; with 100 Gauss-Seidel iterations and 20 substeps it stands, volume exact, no fold), and the bend at
// the ankles and the flopping ears fold the skin along a few edges, which the bound below allows.
void expectArmadilloSettlesWithoutInverting(int target_spheres) {
  if (!std::filesystem::exists(armadilloPath())) GTEST_SKIP() << "shared organ mesh absent: " << armadilloPath();
  Scene s = meshScene(armadilloPath(), kArmadilloScale, target_spheres > 0 ? 0.005 : 0.0048, target_spheres);
  s.solver.gravity = Vec3d(0, -9.81, 0);
  FixedRegion feet;
  feet.min = Vec3d(-1, -1, -1);
  feet.max = Vec3d(1, -0.019, 1);
  s.fixed.push_back(feet);
  auto sim = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  TriangleMesh rest, now;
  ASSERT_TRUE(sim->currentSurface(rest));
  const double v0 = signedVolume(rest);
  for (int f = 0; f < 60; ++f) ASSERT_TRUE(sim->advance(1.0 / 60.0).finite) << "frame " << f;
  ASSERT_TRUE(sim->currentSurface(now));
  const double v = signedVolume(now);
  std::vector<Vec3d> x;
  sim->currentPositions(x);
  double lowest = 0;
  for (const Vec3d& p : x) lowest = std::min(lowest, p.y);
  const int folded = foldedEdges(rest, now);
  std::printf(
      "armadillo %s settle: %s; surface volume %.3f cm3 (rest %.3f, %+.1f%%), folded edges %d, lowest "
      "sphere y %.3f m\n",
      target_spheres > 0 ? "packed" : "lattice", sim->buildNote().c_str(), v * 1e6, v0 * 1e6, 100.0 * (v / v0 - 1.0),
      folded, lowest);
  EXPECT_NEAR(v / v0, 1.0, 0.08);
  EXPECT_LT(folded, int(0.05 * 1.5 * double(rest.triangles.size()))) << "the skin folds over itself";
  EXPECT_GT(lowest, -0.2) << "a sphere fell away from the body";  // hanging from its feet it reaches -0.12 m
}

}  // namespace

TEST(SphereConnectivity, ArmadilloLatticeSettlesWithoutInverting) { expectArmadilloSettlesWithoutInverting(0); }
TEST(SphereConnectivity, ArmadilloPackedSettlesWithoutInverting) { expectArmadilloSettlesWithoutInverting(600); }
