// Tests of the global organ model: the cached precompute (inverse, contact table) and its agreement with the hybrid.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "host/haptics/bem_cache.h"
#include "host/haptics/global_organ_model.h"
#include "host/haptics/hybrid_model.h"
#include "model/input_error.h"

namespace inc {
namespace {
namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("incision_haptic_global_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// An icosphere organ of radius 5 cm (level 1: 80 elements) resting on its bottom (centroids below z = -0.7 R held),
// a coarse tip cloud (fast to factorise; the tests compare precomputes, not accuracy).
GlobalOrganSetup organSetup(const std::string& cache, double E = 3e3, double spacing = 4e-3) {
  GlobalOrganSetup s;
  s.mesh = icosphereMesh(0.05, 1);
  s.supports.assign(s.mesh.triangles.size(), BemBc::kTraction);
  for (std::size_t j = 0; j < s.mesh.triangles.size(); ++j) {
    Vec3d c;
    for (int v : s.mesh.triangles[j]) c += s.mesh.vertices[std::size_t(v)] * (1.0 / 3.0);
    if (c.z < -0.035) s.supports[j] = BemBc::kDisplacement;
  }
  s.material = {E, 0.45};
  s.local.inner_spacing_m = spacing;
  s.local.inner_shells = 2;
  s.local.radius_m = 8e-3;
  s.cache_path = cache;
  s.quiet = true;
  return s;
}

double relativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

void expectSameTable(const OrganContactTable& a, const OrganContactTable& b, double rel) {
  EXPECT_LE(relativeDifference(a.stiffness, b.stiffness), rel);
  EXPECT_LE(relativeDifference(a.surface, b.surface), rel);
}

// The inverse read back from the cache is the one a fresh factorisation gives (1e-10 relative, double), solves
// the same, and a table rebuilt from it (only the local model changed) equals a table built from scratch; the
// unchanged setup loads the table itself.
TEST(HapticGlobal, CachedInverseGivesTheSameAnswerAsAFreshOne) {
  const fs::path dir = scratch("inverse");
  const std::string cache = (dir / "organ.bemcache").string();
  const GlobalOrganModel built(organSetup(cache), 1);
  EXPECT_EQ(built.precompute().source, "built");
  ASSERT_TRUE(fs::exists(cache));
  const GlobalOrganModel loaded(organSetup(cache), 1);
  EXPECT_EQ(loaded.precompute().source, "loaded from the cache");
  expectSameTable(loaded.table(), built.table(), 0.0);  // the stored bits

  // Only the local model differs: the table is stale, the inverse is read.
  const GlobalOrganSetup other = organSetup(cache, 3e3, 2e-3);
  OrganContactTable unused;
  Eigen::MatrixXd a_inv;
  const BemCacheRead r =
      readBemCache(cache, bemCacheKey(other.mesh, other.supports, other.material, 8e-3, 2e-3), unused, a_inv);
  EXPECT_FALSE(r.table);
  ASSERT_TRUE(r.inverse) << r.note;
  EXPECT_NE(r.note.find("another local model"), std::string::npos) << r.note;
  BemModel fresh(other.mesh, other.material);
  fresh.factorBase(other.supports);
  EXPECT_LE(relativeDifference(a_inv, fresh.baseInverse()), 1e-10);
  BemModel from_cache(other.mesh, other.material);
  from_cache.setBaseInverse(other.supports, a_inv);
  const Eigen::VectorXd known = Eigen::VectorXd::LinSpaced(3 * fresh.elementCount(), -1.0, 1.0);
  const Eigen::VectorXd y0 = fresh.solve(known), y1 = from_cache.solve(known);
  EXPECT_LE((y1 - y0).norm(), 1e-10 * y0.norm());

  const GlobalOrganModel rebuilt(organSetup(cache, 3e3, 2e-3), 1);
  EXPECT_EQ(rebuilt.precompute().source, "table rebuilt from the cached inverse");
  const GlobalOrganModel scratch_built(organSetup("", 3e3, 2e-3), 1);
  EXPECT_EQ(scratch_built.precompute().source, "built");
  expectSameTable(rebuilt.table(), scratch_built.table(), 1e-10);
  fs::remove_all(dir);
}

// A changed Young's modulus or mesh makes the cache stale (rebuilt, and the note says why); a corrupt table is
// caught by its checksum and rebuilt from the intact inverse; a truncated file is rebuilt; a cache that cannot be
// written is a note, not an error. Nothing stale or corrupt is ever used: every rebuilt table equals a fresh one.
TEST(HapticGlobal, CacheIsInvalidatedByAChangeAndRebuiltWhenCorrupt) {
  const fs::path dir = scratch("stale");
  const std::string cache = (dir / "organ.bemcache").string();
  const GlobalOrganModel first(organSetup(cache), 1);
  ASSERT_EQ(first.precompute().source, "built");

  const GlobalOrganModel stiffer(organSetup(cache, 6e3), 1);
  EXPECT_EQ(stiffer.precompute().source, "built");
  EXPECT_NE(stiffer.precompute().note.find("E = 3000 Pa"), std::string::npos) << stiffer.precompute().note;
  // Twice as stiff: twice the tip stiffness (linear elasticity), so the stale table was not used.
  EXPECT_LE(relativeDifference(stiffer.table().stiffness, 2.0 * first.table().stiffness), 1e-9);

  GlobalOrganSetup moved = organSetup(cache, 6e3);
  moved.mesh.vertices[0].x += 1e-4;  // one vertex 0.1 mm away
  const GlobalOrganModel other_mesh(moved, 1);
  EXPECT_EQ(other_mesh.precompute().source, "built");
  EXPECT_NE(other_mesh.precompute().note.find("another organ mesh"), std::string::npos) << other_mesh.precompute().note;

  // The cache now holds the moved mesh at 6 kPa: flip one byte in the middle of its contact table.
  {
    std::fstream f(cache, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(96 + 8 * 9 * 80 + 8 * 1000);
    char c = 0;
    f.read(&c, 1);
    c = char(c ^ 0x10);
    f.seekp(96 + 8 * 9 * 80 + 8 * 1000);
    f.write(&c, 1);
  }
  const GlobalOrganModel repaired(moved, 1);
  EXPECT_EQ(repaired.precompute().source, "table rebuilt from the cached inverse");
  EXPECT_NE(repaired.precompute().note.find("corrupt"), std::string::npos) << repaired.precompute().note;
  expectSameTable(repaired.table(), other_mesh.table(), 1e-10);
  EXPECT_EQ(GlobalOrganModel(moved, 1).precompute().source, "loaded from the cache");  // rewritten whole

  fs::resize_file(cache, fs::file_size(cache) - 8);
  const GlobalOrganModel after_truncation(moved, 1);
  EXPECT_EQ(after_truncation.precompute().source, "built");
  EXPECT_NE(after_truncation.precompute().note.find("truncated"), std::string::npos);
  expectSameTable(after_truncation.table(), other_mesh.table(), 1e-10);

  const GlobalOrganModel unwritable(organSetup((dir / "no_such_dir" / "x.bemcache").string()), 1);
  EXPECT_EQ(unwritable.precompute().source, "built");
  EXPECT_NE(unwritable.precompute().note.find("not cached"), std::string::npos) << unwritable.precompute().note;
  fs::remove_all(dir);
}

// The table is the hybrid coupling: at the organ's top element the contact elastic's force on the hand equals
// HybridHapticModel::localTick after touch() (1e-12 relative), and the organ's surface displacement of a step
// equals HybridHapticModel::globalStep's; two hands superpose (linear model). Held elements carry the local model
// alone; a free element's coupled stiffness is softer (the organ gives).
TEST(HapticGlobal, ContactTableIsTheHybridCoupling) {
  GlobalOrganSetup setup = organSetup("", 3e3, 2e-3);
  GlobalOrganModel organ(setup, 2);
  BemModel bem(setup.mesh, setup.material);
  bem.factorBase(setup.supports);
  HybridHapticModel hybrid(bem, setup.local, Material{3e3, 0.45});
  int top = 0, side = 0;
  for (int j = 0; j < bem.elementCount(); ++j) {
    if (bem.centroids()[j].z > bem.centroids()[top].z) top = j;
    if (bem.centroids()[j].x > bem.centroids()[side].x) side = j;
  }
  const Vec3d n = bem.normals()[top], d = n * -2e-3 + Vec3d{3e-4, -2e-4, 0};
  hybrid.touch(top);
  hybrid.globalStep(d, 0.0);
  const Vec3d expected = hybrid.localTick(d).force_n;
  CuttingTool::Elastic hand0 = organ.contactElastic(0), hand1 = organ.contactElastic(1);
  const Vec3d f = hand0(TipContact{true, bem.centroids()[top], d}).force_n;
  EXPECT_LE(norm(f - expected), 1e-12 * norm(expected));
  EXPECT_GT(dot(f, n), 0.0);  // pushed back out
  const Vec3d f_local = hybrid.localOnlyForce(d);
  EXPECT_LT(dot(f, n), dot(f_local, n));  // softer than the held local region
  organ.step();
  EXPECT_EQ(organ.contacts(), 1);
  const Eigen::VectorXd u_top = organ.surfaceDisplacement();
  EXPECT_LE((u_top - hybrid.lastSurfaceDisplacement()).norm(), 1e-12 * u_top.norm());
  EXPECT_GE(organ.maxSurfaceDisplacement_m(), norm(d) * (1.0 - 1e-12));  // the contact element follows the tip

  // A second hand on the side element: the surface displacement is the sum (but at the two contact elements).
  const Vec3d d_side = bem.normals()[side] * -1e-3;
  (void)hand1(TipContact{true, bem.centroids()[side], d_side});
  organ.step();
  EXPECT_EQ(organ.contacts(), 2);
  hybrid.touch(side);
  hybrid.globalStep(d_side, 0.0);
  Eigen::VectorXd sum = u_top + hybrid.lastSurfaceDisplacement();
  sum.segment<3>(3 * top) = u_top.segment<3>(3 * top);
  sum.segment<3>(3 * side) << d_side.x, d_side.y, d_side.z;
  EXPECT_LE((organ.surfaceDisplacement() - sum).norm(), 1e-12 * sum.norm());

  // Out of contact: no force, and the step forgets that hand.
  EXPECT_EQ(norm(hand0(TipContact{}).force_n), 0.0);
  (void)hand1(TipContact{});
  organ.step();
  EXPECT_EQ(organ.contacts(), 0);
  EXPECT_EQ(organ.maxSurfaceDisplacement_m(), 0.0);
  EXPECT_GE(organ.peakSurfaceDisplacement_m(), norm(d) * (1.0 - 1e-12));  // the first contact's, kept
  // A held element: the local model alone.
  int held = -1;
  for (int j = 0; j < bem.elementCount(); ++j)
    if (setup.supports[std::size_t(j)] == BemBc::kDisplacement) held = j;
  ASSERT_GE(held, 0);
  const Eigen::Matrix3d k_held = Eigen::Map<const Eigen::Matrix3d>(organ.table().stiffness.col(held).data());
  EXPECT_LE((k_held - hybrid.worldLocalOnlyStiffness(held)).norm(), 1e-12 * k_held.norm());
}

}  // namespace
}  // namespace inc
