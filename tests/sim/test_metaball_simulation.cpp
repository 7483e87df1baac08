// The scene-built PBD metaball organ: lattice sphere fill, grasper catch/drag/release, probe contact, checkpoints, bad
// input.
#include <gtest/gtest.h>

#include <cmath>

#include "host/assembly/organ_shapes.h"
#include "host/assembly/pbd_builders.h"
#include "host/io/mesh.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "host/sim/grasper.h"
#include "host/sim/metaball_simulation.h"
#include "model/input_error.h"
#include "tests/support/repo_paths.h"
#include "tests/support/temp_dir.h"

using namespace inc;

namespace {

// A 6 x 4 x 2 cm block of 1 cm lattice cells, clamped at x = 0, with a grasper above its free end that
// closes at t = 0.105 s (the first frame starting after it: 7/60 s), lifts by 2 cm until 0.5 s and releases.
Scene graspScene() {
  Scene s;
  s.file = "<test>";
  s.name = "grasp";
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.center = Vec3d(0.03, 0, 0);
  s.geometry.size = Vec3d(0.06, 0.04, 0.02);
  s.geometry.spacing = 0.01;
  s.material.youngs_modulus_pa = 2.0e4;
  s.material.damping_per_s = 5.0;
  s.models.pbd_metaballs = true;
  s.pbd.iterations = 10;
  s.pbd.solver = "gauss_seidel";
  FixedRegion fx;
  fx.min = Vec3d(-1, -1, -1);
  fx.max = Vec3d(0.011, 1, 1);
  s.fixed.push_back(fx);
  ToolSpec g;
  g.name = "jaws";
  g.kind = "grasper";
  g.radius = 0.004;
  g.path.push_back({0.105, Vec3d(0.055, 0.0, 0.012), Vec3d(0, 0, -1)});
  g.path.push_back({0.5, Vec3d(0.055, 0.0, 0.032), Vec3d(0, 0, -1)});
  s.tools.push_back(g);
  return s;
}

}  // namespace

TEST(MetaballSimulation, LatticeFillOfABoxHasItsMassAndOverlapLinks) {
  const Scene s = graspScene();
  const MetaballModel mb = buildSceneMetaballs(compileScene(s));
  ASSERT_EQ(mb.size(), 6u * 4u * 2u);
  double mass = 0;
  for (double m : mb.masses) mass += m;
  EXPECT_NEAR(mass, s.material.density_kg_m3 * 0.06 * 0.04 * 0.02, 1e-12);
  // radius 0.75 s: face (s) and edge (1.41 s) neighbours overlap, corner (1.73 s) ones do not.
  std::size_t face = 0, edge = 0;
  for (std::size_t l = 0; l < mb.links.size(); ++l) {
    const double d = mb.link_rest_lengths[l];
    EXPECT_LT(d, mb.rest_radii[mb.links[l][0]] + mb.rest_radii[mb.links[l][1]]);
    if (std::fabs(d - 0.01) < 1e-9) ++face;
    if (std::fabs(d - 0.01 * std::sqrt(2.0)) < 1e-9) ++edge;
  }
  EXPECT_EQ(face + edge, mb.links.size());
  EXPECT_EQ(face, 5u * 4 * 2 + 6u * 3 * 2 + 6u * 4 * 1);  // lattice face-neighbour pairs
}

TEST(MetaballSimulation, GrasperCatchesDragsAndReleases) {
  const Scene s = graspScene();
  auto sim = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  std::vector<Vec3d> at_grasp, x;
  FrameReport r;
  for (int f = 0; f < 7; ++f) ASSERT_TRUE(sim->advance(1.0 / 60.0).finite);
  sim->currentPositions(at_grasp);  // the grasp happens at the start of the next frame, on these positions
  const double t_grasp = 7.0 / 60.0;
  const Vec3d tip(0.055, 0.0, 0.012 + 0.02 * (t_grasp - 0.105) / 0.395);
  std::vector<int> expected;
  for (std::size_t i = 0; i < at_grasp.size(); ++i)
    if (norm(at_grasp[i] - tip) <= 0.004 + 0.01 + 0.0075) expected.push_back(int(i));  // the clamped end is 5 cm away
  for (int f = 7; f < 30; ++f) {                                                       // to t = 0.5 s
    r = sim->advance(1.0 / 60.0);
    ASSERT_TRUE(r.finite);
  }
  ASSERT_GT(expected.size(), 0u);
  EXPECT_EQ(int(r.counters.at("grasped")), int(expected.size()));
  sim->currentPositions(x);
  // The caught spheres follow the jaws (lift 0.032 - tip.z) through the compliant attachment (1e-6 m/N:
  // under 10% lag).
  double lift = 0;
  for (int i : expected) lift += x[i].z - at_grasp[i].z;
  lift /= double(expected.size());
  EXPECT_NEAR(lift, 0.032 - tip.z, 0.1 * (0.032 - tip.z));
  EXPECT_GT(r.max_displacement, 0.015);
  // Released at 0.5 s: nothing held, and the lifted end falls back under gravity.
  for (int f = 0; f < 30; ++f) r = sim->advance(1.0 / 60.0);
  EXPECT_EQ(r.counters.at("grasped"), 0.0);
  std::vector<Vec3d> y;
  sim->currentPositions(y);
  double zmax_before = -1, zmax_after = -1;
  for (std::size_t i = 0; i < x.size(); ++i) {
    zmax_before = std::max(zmax_before, x[i].z);
    zmax_after = std::max(zmax_after, y[i].z);
  }
  EXPECT_LT(zmax_after, zmax_before - 0.005);
}

TEST(MetaballSimulation, ProbePushesSpheresOutOfItsCapsule) {
  Scene s = graspScene();
  s.tools[0].kind = "probe";
  s.tools[0].length = 0.03;
  s.tools[0].path = {{0.0, Vec3d(0.045, 0.0, 0.02), Vec3d(0, 0, -1)}, {0.3, Vec3d(0.045, 0.0, 0.008), Vec3d(0, 0, -1)}};
  auto sim = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  for (int f = 0; f < 24; ++f) ASSERT_TRUE(sim->advance(1.0 / 60.0).finite);
  std::vector<Vec3d> x;
  sim->currentPositions(x);
  const auto cap = toolCapsule(s.tools[0], toolPoseAt(s.tools[0], 0.4));
  double min_gap = 1e9;
  for (const Vec3d& c : x) min_gap = std::min(min_gap, pbd::capsuleDistance(c, cap) - 0.0075);
  EXPECT_GT(min_gap, -1e-4);  // no sphere inside the probe (0.1 mm: the last iteration's constraints)
}

TEST(MetaballSimulation, CheckpointRestoreReplaysExactly) {
  const Scene s = graspScene();
  auto sim = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
  for (int f = 0; f < 10; ++f) sim->advance(1.0 / 60.0);
  sim->saveCheckpoint();
  for (int f = 0; f < 5; ++f) sim->advance(1.0 / 60.0);
  std::vector<Vec3d> a, b;
  sim->currentPositions(a);
  sim->restoreCheckpoint();
  for (int f = 0; f < 5; ++f) sim->advance(1.0 / 60.0);
  sim->currentPositions(b);
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].z, b[i].z);
}

TEST(MetaballSimulation, BadSettingsAreInputErrors) {
  Scene s = graspScene();
  s.pbd.solver = "sor";
  EXPECT_THROW(makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32), InputError);
  s = graspScene();
  s.pbd.iterations = 0;
  EXPECT_THROW(makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32), InputError);
  s = graspScene();
  s.geometry.spacing = -0.01;
  EXPECT_THROW(makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32), InputError);
}

// The shipped scene loads, fills to a liver-sized sphere count (the paper's Table 1 case is 570) and its
// grasper catches the front edge.
TEST(MetaballSimulation, LiverGraspSceneRunsAndGrasps) {
  const Scene s = loadSceneFile(test::sourcePath("scenes/liver_grasp.json"));
  ASSERT_TRUE(s.models.pbd_metaballs);
  auto sim = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  EXPECT_GT(sim->particleCount(), 450u);
  EXPECT_LT(sim->particleCount(), 700u);
  FrameReport r;
  for (int f = 0; f < 18; ++f) {
    r = sim->advance(s.solver.frame_dt);
    ASSERT_TRUE(r.finite);
  }
  EXPECT_GT(r.counters.at("grasped"), 0.0);
  EXPECT_LT(r.max_displacement, 0.05);
}

// A clamp box that holds no sphere centre (a thin slab between two layers of a 1 cm lattice) is refused with
// the key and the distance to the nearest centre; one that holds a layer fixes exactly that layer.
TEST(MetaballSimulation, FixedBoxHoldingNoSphereIsAnInputError) {
  const MetaballModel mb = makeLatticeMetaballs(Vec3d(0, 0, 0), Vec3d(0.04, 0.02, 0.02), 0.01, 0.75, 1000.0);
  MetaballPbdOptions opt;
  opt.volume_samples = 0;
  opt.file = "scene.json";
  FixedRegion between;  // lattice centres at x = 0, 0.01, ...: nothing in [0.002, 0.008]
  between.min = Vec3d(0.002, -1, -1);
  between.max = Vec3d(0.008, 1, 1);
  opt.fixed = {between};
  try {
    buildMetaballPbdModel<double>(mb, opt);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("scene.json"), std::string::npos) << what;
    EXPECT_NE(what.find("fixed[0]"), std::string::npos) << what;
    EXPECT_NE(what.find("2.000000 mm"), std::string::npos) << what;  // the layers are 2 mm outside the slab
  }
  FixedRegion layer = between;
  layer.min.x = -0.001;
  opt.fixed = {layer};
  const PbdModel<double> m = buildMetaballPbdModel<double>(mb, opt);
  int fixed = 0;
  for (std::size_t i = 0; i < m.size(); ++i) fixed += m.inv_mass[i] == 0.0 ? 1 : 0;
  EXPECT_EQ(fixed, 9);  // the x = 0 layer: 3 x 3 spheres
}

// The packer's mesh checks name the scene key: a closed, manifold mesh of two interpenetrating boxes is
// self-intersecting, and a scene that packs it (pbd.target_spheres > 0) is refused under geometry.mesh (it was
// once refused under "mesh", a key no scene has).
TEST(MetaballSimulation, PackerRefusesASelfIntersectingMeshUnderGeometryMesh) {
  const test::TempDir tmp("packer_twin_boxes");
  TriangleMesh twin = makeBoxMesh({0.05, 0.05, 0.05}, 2);
  const TriangleMesh other = makeBoxMesh({0.05, 0.05, 0.05}, 2, Vec3d{0.03, 0.02, 0.01});
  const int base = int(twin.vertices.size());
  twin.vertices.insert(twin.vertices.end(), other.vertices.begin(), other.vertices.end());
  for (auto t : other.triangles) twin.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  const std::string path = tmp.str() + "/twin.obj";
  writeObj(path, twin);
  Scene s;
  s.file = "twin.json";
  s.geometry.kind = GeometrySpec::Kind::Mesh;
  s.geometry.mesh_path = path;
  s.geometry.spacing = 0.02;
  s.models.pbd_metaballs = true;
  s.pbd.target_spheres = 60;
  s.fixed = {FixedRegion{Vec3d(-1, -1, -1), Vec3d(1, 1, -0.04)}};
  try {
    makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float64);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "twin.json") << e.what();
    EXPECT_EQ(e.key(), "geometry.mesh") << e.what();
    EXPECT_NE(std::string(e.reason()).find("self-intersecting"), std::string::npos) << e.what();
  }
}
