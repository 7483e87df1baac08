// Tests for packOrgan: containment, coverage, protrusion, links and masses, determinism, cache, real organs, bad
// meshes.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "host/assembly/metaball_packing.h"
#include "host/assembly/organ_shapes.h"
#include "host/io/triangle_bvh.h"
#include "model/input_error.h"
#include "tests/support/repo_paths.h"
#include "tests/support/temp_dir.h"

namespace inc {
namespace {

PackingOptions smallOptions(int spheres = 120) {
  PackingOptions o;
  o.target_spheres = spheres;
  o.samples = 8000;
  return o;
}

struct Lcg {
  std::uint64_t s = 12345;
  double next() {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(s >> 11) * (1.0 / 9007199254740992.0);
  }
};

bool inUnion(const MetaballModel& m, const Vec3d& p) {
  for (std::size_t i = 0; i < m.size(); ++i)
    if (norm2(p - m.rest_centers[i]) <= m.rest_radii[i] * m.rest_radii[i]) return true;
  return false;
}

// Fraction of uniformly random points of the analytic solid (rejection sampling in its box) inside the union.
double analyticCoverage(const MetaballModel& m, const Vec3d& lo, const Vec3d& hi,
                        const std::function<bool(const Vec3d&)>& inside, int points = 4000) {
  Lcg rng;
  int in = 0, cov = 0;
  while (in < points) {
    const Vec3d p{lo.x + (hi.x - lo.x) * rng.next(), lo.y + (hi.y - lo.y) * rng.next(),
                  lo.z + (hi.z - lo.z) * rng.next()};
    if (!inside(p)) continue;
    ++in;
    cov += inUnion(m, p);
  }
  return double(cov) / in;
}

double diagonal(const TriangleMesh& mesh) {
  const MeshReport r = analyzeMesh(mesh);
  return norm(r.bbox_max - r.bbox_min);
}

// Facts every pack must satisfy: centres inside (ray parity), bounded protrusion, consistent links and masses.
void checkPackInvariants(const TriangleMesh& mesh, const PackedOrgan& p, const PackingOptions& o) {
  const MetaballModel& m = p.model;
  ASSERT_GT(m.size(), 0u);
  ASSERT_EQ(m.rest_radii.size(), m.size());
  ASSERT_EQ(m.masses.size(), m.size());
  const pack::SurfaceDistance sd(mesh);
  const double diag = diagonal(mesh);
  double worst = 0.0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    EXPECT_TRUE(sd.insideByRays(m.rest_centers[i])) << "sphere " << i << " centre outside the surface";
    EXPECT_GT(m.rest_radii[i], 0.0);
    // How far the sphere reaches beyond the surface: r + sdf(c). Bounded by the option; bridging may add a little.
    const double reach = m.rest_radii[i] + sd.signedDistance(m.rest_centers[i]).distance;
    worst = std::max(worst, reach);
  }
  EXPECT_LE(worst, 1.5 * o.max_protrusion * diag + 1e-12) << "a sphere reaches far outside the surface";
  EXPECT_NEAR(worst, p.report.max_protrusion, 1e-9 * diag);
  // Links: exactly the overlapping pairs, sorted, with their rest lengths.
  std::size_t expected = 0;
  for (std::size_t i = 0; i < m.size(); ++i)
    for (std::size_t j = i + 1; j < m.size(); ++j)
      expected += norm(m.rest_centers[i] - m.rest_centers[j]) < m.rest_radii[i] + m.rest_radii[j];
  EXPECT_EQ(m.links.size(), expected);
  ASSERT_EQ(m.link_rest_lengths.size(), m.links.size());
  for (std::size_t l = 0; l < m.links.size(); ++l) {
    const auto [a, b] = m.links[l];
    ASSERT_LT(a, b);
    EXPECT_DOUBLE_EQ(m.link_rest_lengths[l], norm(m.rest_centers[std::size_t(a)] - m.rest_centers[std::size_t(b)]));
    if (l) {
      EXPECT_TRUE(m.links[l - 1] < m.links[l]);
    }
  }
  EXPECT_EQ(p.report.components, 1);
  // Masses: positive, summing to density * enclosed volume (rel 1e-9).
  double mass = 0.0;
  for (double x : m.masses) {
    EXPECT_GT(x, 0.0);
    mass += x;
  }
  EXPECT_NEAR(mass, o.density_kg_m3 * p.report.mesh_volume, 1e-9 * mass);
  EXPECT_LE(p.report.spheres, o.target_spheres);
}

TEST(Packing, SphereCoveredContainedAndNearTargetCount) {
  const double R = 0.05;
  const TriangleMesh mesh = makeSphereMesh(R, 12);
  const PackingOptions o = smallOptions(120);
  const PackedOrgan p = packOrgan(mesh, o);
  checkPackInvariants(mesh, p, o);
  EXPECT_GE(p.report.spheres, 60) << "the radius cap should bring the count near the target";
  EXPECT_GE(p.report.coverage, 0.95);
  // Independent estimate on the analytic ball, shrunk by the polyhedral sagitta (2e-4 m here).
  const double cov =
      analyticCoverage(p.model, Vec3d{-R, -R, -R}, Vec3d{R, R, R}, [&](const Vec3d& x) { return norm(x) < R - 5e-4; });
  EXPECT_GE(cov, 0.95);
  // Surface deviation is reported and bounded (2% of the diagonal; the protrusion bound is 1%).
  const double diag = diagonal(mesh);
  EXPECT_GT(p.report.surface_max, 0.0);
  EXPECT_LE(p.report.surface_max, 0.02 * diag);
  EXPECT_LE(p.report.surface_mean, p.report.surface_max);
  EXPECT_LE(p.report.union_max, 0.05 * diag);
}

TEST(Packing, BoxCoveredIncludingCorners) {
  const Vec3d half{0.05, 0.035, 0.025};
  const TriangleMesh mesh = makeBoxMesh(half, 4);
  const PackingOptions o = smallOptions(150);
  const PackedOrgan p = packOrgan(mesh, o);
  checkPackInvariants(mesh, p, o);
  EXPECT_GE(p.report.coverage, 0.95);
  const double cov = analyticCoverage(p.model, half * -1.0, half, [](const Vec3d&) { return true; });
  EXPECT_GE(cov, 0.95);
  // A sphere union cannot fill a convex corner: the corner vertices are the worst points (measured 3.7%).
  EXPECT_LE(p.report.surface_max, 0.05 * diagonal(mesh));
}

TEST(Packing, TorusCoveredAndConnectedAroundTheHole) {
  const double Rm = 0.035, r = 0.015;
  const TriangleMesh mesh = makeTorusMesh(Rm, r, 48, 16);
  const PackingOptions o = smallOptions(120);
  const PackedOrgan p = packOrgan(mesh, o);
  checkPackInvariants(mesh, p, o);
  EXPECT_GE(p.report.coverage, 0.95);
  // Analytic torus shrunk by the polygon sagitta of the coarse tessellation.
  const double cov =
      analyticCoverage(p.model, Vec3d{-Rm - r, -Rm - r, -r}, Vec3d{Rm + r, Rm + r, r}, [&](const Vec3d& x) {
        const double q = std::sqrt(x.x * x.x + x.y * x.y) - Rm;
        return q * q + x.z * x.z < (0.95 * r) * (0.95 * r);
      });
  EXPECT_GE(cov, 0.95);
  // Nothing may fill the hole: the axis of the torus lies outside every sphere.
  for (double z : {-0.01, 0.0, 0.01}) EXPECT_FALSE(inUnion(p.model, Vec3d{0.0, 0.0, z}));
}

TEST(Packing, DeterministicAcrossRunsAndThreadCounts) {
  const TriangleMesh mesh = makeLiverLikeMesh({2000, 0.2, 0});
  const PackingOptions o = smallOptions(80);
  const PackedOrgan a = packOrgan(mesh, o);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const PackedOrgan b = packOrgan(mesh, o);
  omp_set_num_threads(threads);
  ASSERT_EQ(a.model.size(), b.model.size());
  for (std::size_t i = 0; i < a.model.size(); ++i) {
    EXPECT_EQ(a.model.rest_centers[i].x, b.model.rest_centers[i].x);
    EXPECT_EQ(a.model.rest_centers[i].y, b.model.rest_centers[i].y);
    EXPECT_EQ(a.model.rest_centers[i].z, b.model.rest_centers[i].z);
    EXPECT_EQ(a.model.rest_radii[i], b.model.rest_radii[i]);
    EXPECT_EQ(a.model.masses[i], b.model.masses[i]);
  }
  EXPECT_EQ(a.model.links, b.model.links);
  EXPECT_EQ(a.report.coverage, b.report.coverage);
}

TEST(Packing, LiverLikeShapeReferenceCase) {
  const TriangleMesh mesh = makeLiverLikeMesh();
  PackingOptions o;  // the defaults: 550 spheres, the paper's Table 1 liver (570 spheres, 8128 vertices)
  o.samples = 20000;
  const PackedOrgan p = packOrgan(mesh, o);
  checkPackInvariants(mesh, p, o);
  EXPECT_GE(p.report.spheres, 450);
  EXPECT_GE(p.report.coverage, 0.97);
}

TEST(Packing, CacheHitsMissesAndCorruption) {
  const TriangleMesh mesh = makeSphereMesh(0.04, 6);
  PackingOptions o = smallOptions(40);
  o.samples = 3000;
  const test::TempDir tmp("packing_cache");
  const std::string path = tmp.file("cache.pack");
  const PackedOrgan a = loadOrBuildPack(mesh, o, path);
  EXPECT_FALSE(a.report.from_cache);
  ASSERT_TRUE(std::filesystem::exists(path));
  const PackedOrgan b = loadOrBuildPack(mesh, o, path);
  EXPECT_TRUE(b.report.from_cache);
  ASSERT_EQ(a.model.size(), b.model.size());
  for (std::size_t i = 0; i < a.model.size(); ++i) {
    EXPECT_EQ(a.model.rest_radii[i], b.model.rest_radii[i]);
    EXPECT_EQ(a.model.masses[i], b.model.masses[i]);
  }
  EXPECT_EQ(a.model.links, b.model.links);
  EXPECT_EQ(a.report.coverage, b.report.coverage);
  EXPECT_EQ(a.report.key, b.report.key);
  // A changed option or mesh invalidates the cache.
  o.max_protrusion = 0.02;
  EXPECT_NE(packCacheKey(mesh, o), a.report.key);
  EXPECT_FALSE(loadOrBuildPack(mesh, o, path).report.from_cache);
  TriangleMesh moved = mesh;
  moved.vertices[0].x += 1e-9;
  EXPECT_NE(packCacheKey(moved, o), packCacheKey(mesh, o));
  // A truncated file is rebuilt, not trusted.
  const auto size = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, size / 2);
  const PackedOrgan c = loadOrBuildPack(mesh, o, path);
  EXPECT_FALSE(c.report.from_cache);
  EXPECT_TRUE(loadOrBuildPack(mesh, o, path).report.from_cache);
  EXPECT_EQ(defaultPackCachePath("scenes/liver.obj"), "scenes/liver.obj.pack");
  const std::string line = describePack(c.report);
  EXPECT_NE(line.find(std::to_string(c.report.spheres) + " spheres"), std::string::npos) << line;
  EXPECT_NE(line.find("coverage"), std::string::npos) << line;
}

TEST(Packing, RealOrganMeshes) {
  const std::string dir = test::sharedPath("organs/");
  bool any = false;
  for (const char* name : {"liver2.obj", "liver-smooth.obj"}) {
    const std::string path = dir + name;
    if (!std::filesystem::exists(path)) continue;
    any = true;
    SCOPED_TRACE(path);
    const TriangleMesh mesh = loadMesh(path);
    const PackingOptions o = smallOptions(150);
    const PackedOrgan p = packOrgan(mesh, o, path);
    checkPackInvariants(mesh, p, o);
    EXPECT_GE(p.report.coverage, 0.95);
    if (std::string(name) == "liver-smooth.obj") {
      // It has a few locally folded faces: tolerated by default and said so, rejected with no tolerance.
      EXPECT_NE(p.report.repairs.find("tolerated"), std::string::npos) << p.report.repairs;
      PackingOptions strict = o;
      strict.max_self_intersecting_fraction = 0.0;
      EXPECT_THROW(packOrgan(mesh, strict, path), InputError);
    }
  }
  if (!any) GTEST_SKIP() << "no organ meshes in " << dir << " (shared data absent)";
}

template <typename F>
std::string inputErrorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Packing, BadMeshesAreRejectedWithAReason) {
  const PackingOptions o = smallOptions(20);
  const TriangleMesh box = makeBoxMesh({0.05, 0.05, 0.05}, 2);
  TriangleMesh open = box;
  open.triangles.pop_back();
  EXPECT_NE(inputErrorOf([&] { packOrgan(open, o, "open.obj"); }).find("open surface"), std::string::npos);
  TriangleMesh nonmanifold = box;
  nonmanifold.triangles.push_back(box.triangles[0]);
  EXPECT_NE(inputErrorOf([&] { packOrgan(nonmanifold, o); }).find("non-manifold"), std::string::npos);
  TriangleMesh inconsistent = box;
  std::swap(inconsistent.triangles[3][1], inconsistent.triangles[3][2]);
  EXPECT_NE(inputErrorOf([&] { packOrgan(inconsistent, o); }).find("inconsistent orientation"), std::string::npos);
  TriangleMesh flat = box;
  for (auto& v : flat.vertices) v.z *= 1e-10;
  EXPECT_NE(inputErrorOf([&] { packOrgan(flat, o); }).find("zero volume"), std::string::npos);
  // Two interpenetrating boxes in one mesh: closed and manifold, but self-intersecting everywhere they cross.
  TriangleMesh twin = box;
  const TriangleMesh other = makeBoxMesh({0.05, 0.05, 0.05}, 2, Vec3d{0.03, 0.02, 0.01});
  const int base = int(twin.vertices.size());
  twin.vertices.insert(twin.vertices.end(), other.vertices.begin(), other.vertices.end());
  for (auto t : other.triangles) twin.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  EXPECT_NE(inputErrorOf([&] { packOrgan(twin, o); }).find("self-intersecting"), std::string::npos);
  TriangleMesh nan = box;
  nan.vertices[2].y = std::nan("");
  EXPECT_NE(inputErrorOf([&] { packOrgan(nan, o); }).find("non-finite"), std::string::npos);
  EXPECT_NE(inputErrorOf([&] { packOrgan(TriangleMesh{}, o); }).find("empty"), std::string::npos);
  TriangleMesh bad_index = box;
  bad_index.triangles[0][1] = 1000;
  EXPECT_NE(inputErrorOf([&] { packOrgan(bad_index, o); }).find("out of range"), std::string::npos);
  PackingOptions bad = o;
  bad.target_spheres = 0;
  EXPECT_NE(inputErrorOf([&] { packOrgan(box, bad); }).find("target_spheres"), std::string::npos);
  bad = o;
  bad.max_protrusion = -1.0;
  EXPECT_NE(inputErrorOf([&] { packOrgan(box, bad); }).find("max_protrusion"), std::string::npos);
}

TEST(Packing, InwardOrientedMeshIsFlippedAndSaysSo) {
  TriangleMesh mesh = makeSphereMesh(0.03, 4);
  for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  PackingOptions o = smallOptions(20);
  o.samples = 3000;
  const PackedOrgan p = packOrgan(mesh, o);
  EXPECT_NE(p.report.repairs.find("flipped"), std::string::npos);
  EXPECT_GT(p.report.mesh_volume, 0.0);
  EXPECT_GE(p.report.coverage, 0.95);
}

TEST(Packing, ProgressIsReportedInOrder) {
  PackingOptions o = smallOptions(20);
  o.samples = 2000;
  std::vector<std::string> stages;
  o.progress = [&](const char* stage, double f) {
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
    if (stages.empty() || stages.back() != stage) stages.push_back(stage);
  };
  packOrgan(makeSphereMesh(0.03, 4), o);
  ASSERT_GE(stages.size(), 4u);
  EXPECT_EQ(stages.front(), "checked mesh");
  EXPECT_EQ(stages.back(), "done");
}

TEST(Packing, SeparateShellsStaySeparateGroups) {
  // Two disjoint balls in one mesh: valid input; each gets its own spheres and no sphere bridges the gap.
  TriangleMesh two = makeSphereMesh(0.02, 5, Vec3d{-0.03, 0.0, 0.0});
  const TriangleMesh b = makeSphereMesh(0.02, 5, Vec3d{0.03, 0.0, 0.0});
  const int base = int(two.vertices.size());
  two.vertices.insert(two.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto t : b.triangles) two.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  PackingOptions o = smallOptions(60);
  o.samples = 4000;
  const PackedOrgan p = packOrgan(two, o);
  EXPECT_EQ(p.report.components, 2);
  EXPECT_EQ(p.report.bridged, 0);
  EXPECT_GE(p.report.coverage, 0.95);
  for (std::size_t i = 0; i < p.model.size(); ++i)
    EXPECT_LT(std::fabs(p.model.rest_centers[i].x) + p.model.rest_radii[i], 0.05 + 0.011 * diagonal(two) + 1e-12);
  EXPECT_FALSE(inUnion(p.model, Vec3d{0.0, 0.0, 0.0}));
}

TEST(PackingBvh, RayParityAndSignedDistanceAgreeOnABox) {
  const TriangleMesh box = makeBoxMesh({1.0, 1.0, 1.0}, 3);
  const pack::SurfaceDistance sd(box);
  Lcg rng;
  for (int n = 0; n < 500; ++n) {
    const Vec3d p{3.0 * rng.next() - 1.5, 3.0 * rng.next() - 1.5, 3.0 * rng.next() - 1.5};
    const bool inside = std::fabs(p.x) < 1.0 && std::fabs(p.y) < 1.0 && std::fabs(p.z) < 1.0;
    EXPECT_EQ(sd.insideByRays(p), inside) << p.x << " " << p.y << " " << p.z;
    const double d = sd.signedDistance(p).distance;
    // Exact box SDF.
    const Vec3d q{std::fabs(p.x) - 1.0, std::fabs(p.y) - 1.0, std::fabs(p.z) - 1.0};
    const Vec3d qo{std::max(q.x, 0.0), std::max(q.y, 0.0), std::max(q.z, 0.0)};
    const double exact = norm(qo) + std::min(std::max({q.x, q.y, q.z}), 0.0);
    EXPECT_NEAR(d, exact, 1e-12);
  }
}

}  // namespace
}  // namespace inc
