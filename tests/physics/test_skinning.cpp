// Tests for skinning: binding (exact k-nearest, partition of unity, continuity), rest and rigid-motion exactness,
// normals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "cpu_fallback/skinning_cpu.h"
#include "host/assembly/metaball_packing.h"
#include "host/assembly/organ_shapes.h"
#include "host/assembly/skin_binding.h"
#include "model/input_error.h"
#include "physics/skinning.h"

namespace inc {
namespace {
using cpu::skinSurfaceCpu;
using cpu::vertexNormalsCpu;

// A small packed organ shared by the tests (packing once keeps the suite fast).
const PackedOrgan& liverPack() {
  static const PackedOrgan p = [] {
    PackingOptions o;
    o.target_spheres = 100;
    o.samples = 6000;
    return packOrgan(makeLiverLikeMesh({3000, 0.2, 0}), o);
  }();
  return p;
}
const TriangleMesh& liverMesh() {
  static const TriangleMesh m = makeLiverLikeMesh({3000, 0.2, 0});
  return m;
}

Mat3d rotation(const Vec3d& axis, double angle) {  // Rodrigues
  const Vec3d a = axis * (1.0 / norm(axis));
  const double c = std::cos(angle), s = std::sin(angle);
  Mat3d K = Mat3d::fromRows({0, -a.z, a.y}, {a.z, 0, -a.x}, {-a.y, a.x, 0});
  return Mat3d::identity() + K * s + (K * K) * (1.0 - c);
}

TEST(SkinBinding, ExactNearestPartitionOfUnityAndNonNegative) {
  const PackedOrgan& p = liverPack();
  const TriangleMesh& mesh = liverMesh();
  const int k = 4;
  const SkinBinding b = bindSkin(mesh, p.model, k);
  ASSERT_EQ(b.vertexCount(), int(mesh.vertices.size()));
  const auto& C = p.model.rest_centers;
  const auto& R = p.model.rest_radii;
  for (int v = 0; v < b.vertexCount(); ++v) {
    double sum = 0.0;
    for (int j = 0; j < k; ++j) {
      const double w = b.weight[std::size_t(v * k + j)];
      EXPECT_GE(w, 0.0);
      sum += w;
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    // Brute force: the bound spheres are the k smallest d_i = |v - c_i| - r_i, in order.
    if (v % 37 == 0) {
      std::vector<std::pair<double, int>> all;
      for (std::size_t i = 0; i < C.size(); ++i)
        all.push_back({norm(mesh.vertices[std::size_t(v)] - C[i]) - R[i], int(i)});
      std::sort(all.begin(), all.end());
      for (int j = 0; j < k; ++j)
        EXPECT_EQ(b.sphere[std::size_t(v * k + j)], all[std::size_t(j)].second) << "vertex " << v;
      EXPECT_GT(b.weight[std::size_t(v * k)], 0.0);
    }
  }
}

TEST(SkinBinding, WeightsAreContinuousInTheVertexPosition) {
  // Weights as a function of position: moving a vertex by 1e-7 of the organ size changes them by O(1e-7 / spacing).
  const PackedOrgan& p = liverPack();
  TriangleMesh a = liverMesh(), b = a;
  for (auto& v : b.vertices) v += Vec3d{1e-8, -2e-8, 1.5e-8};
  const SkinBinding ba = bindSkin(a, p.model, 4), bb = bindSkin(b, p.model, 4);
  double worst = 0.0;
  for (int v = 0; v < ba.vertexCount(); ++v)
    for (int j = 0; j < 4; ++j) {
      // Compare per sphere id: a sphere leaving the set does so with weight ~0.
      const int s = ba.sphere[std::size_t(v * 4 + j)];
      double wb = 0.0;
      for (int m = 0; m < 4; ++m)
        if (bb.sphere[std::size_t(v * 4 + m)] == s && bb.weight[std::size_t(v * 4 + m)] > 0.0)
          wb = bb.weight[std::size_t(v * 4 + m)];
      worst = std::max(worst, std::fabs(ba.weight[std::size_t(v * 4 + j)] - wb));
    }
  EXPECT_LT(worst, 1e-3);
  EXPECT_EQ(skin::bindWeight(1.0, 1.0), 0.0);  // the first unbound sphere's weight would be exactly zero
  EXPECT_EQ(skin::bindWeight(0.0, 1.0), 1.0);
}

template <typename T>
void restAndRigid(double tol_rel) {
  const PackedOrgan& p = liverPack();
  const TriangleMesh& mesh = liverMesh();
  const SkinArrays<T> arr = skinArrays<T>(bindSkin(mesh, p.model, 4));
  const auto view = arr.view();
  const int nv = view.vertex_count;
  const double scale = 0.2;  // organ size, m
  std::vector<Vec3<T>> out(static_cast<std::size_t>(nv));
  // At rest the skin reproduces the input mesh (1e-6 relative for float).
  skinSurfaceCpu(view, arr.rest_centres.data(), static_cast<const Mat3<T>*>(nullptr), out.data());
  for (int v = 0; v < nv; ++v)
    EXPECT_LE(norm(Vec3d(out[std::size_t(v)]) - mesh.vertices[std::size_t(v)]), tol_rel * scale) << v;
  // Rigid motion of all spheres (centres c -> R c + t, rotations R) moves the surface rigidly.
  const Mat3d Rd = rotation({0.3, -1.0, 0.5}, 0.9);
  const Vec3d t{0.05, -0.02, 0.11};
  std::vector<Vec3<T>> centres;
  std::vector<Mat3<T>> rots(p.model.size(), Mat3<T>(Rd));
  for (const auto& c : p.model.rest_centers) centres.push_back(Vec3<T>(Rd * c + t));
  skinSurfaceCpu(view, centres.data(), rots.data(), out.data());
  for (int v = 0; v < nv; ++v)
    EXPECT_LE(norm(Vec3d(out[std::size_t(v)]) - (Rd * mesh.vertices[std::size_t(v)] + t)), tol_rel * scale) << v;
  // Normals rotate with the surface: compare against the rest normals rotated.
  std::vector<Vec3<T>> rest_n(static_cast<std::size_t>(nv)), n(static_cast<std::size_t>(nv));
  std::vector<Vec3<T>> rest_x(arr.rest_vertices);
  vertexNormalsCpu(nv, rest_x.data(), arr.triangles.data(), arr.tri_offsets.data(), arr.tri_of_vertex.data(),
                   rest_n.data());
  vertexNormalsCpu(nv, out.data(), arr.triangles.data(), arr.tri_offsets.data(), arr.tri_of_vertex.data(), n.data());
  for (int v = 0; v < nv; ++v) {
    EXPECT_NEAR(norm(Vec3d(rest_n[std::size_t(v)])), 1.0, 1e-5);
    EXPECT_LE(norm(Vec3d(n[std::size_t(v)]) - Rd * Vec3d(rest_n[std::size_t(v)])), 1e3 * tol_rel) << v;
  }
}

TEST(Skinning, RestAndRigidMotionExactDouble) { restAndRigid<double>(1e-12); }
TEST(Skinning, RestAndRigidMotionExactFloat) { restAndRigid<float>(1e-6); }

TEST(Skinning, TranslationOnlyWithoutRotations) {
  const PackedOrgan& p = liverPack();
  const TriangleMesh& mesh = liverMesh();
  const SkinArrays<double> arr = skinArrays<double>(bindSkin(mesh, p.model, 6));
  std::vector<Vec3d> centres;
  const Vec3d t{-0.3, 0.1, 0.2};
  for (const auto& c : p.model.rest_centers) centres.push_back(c + t);
  std::vector<Vec3d> out(mesh.vertices.size());
  skinSurfaceCpu(arr.view(), centres.data(), static_cast<const Mat3d*>(nullptr), out.data());
  for (std::size_t v = 0; v < out.size(); ++v) EXPECT_LE(norm(out[v] - (mesh.vertices[v] + t)), 1e-13);
}

TEST(Skinning, LocalMotionMovesOnlyNearbySkin) {
  // Moving one sphere moves exactly the vertices bound to it, by its weight times its displacement.
  const PackedOrgan& p = liverPack();
  const TriangleMesh& mesh = liverMesh();
  const SkinBinding b = bindSkin(mesh, p.model, 4);
  const SkinArrays<double> arr = skinArrays<double>(b);
  std::vector<Vec3d> centres = p.model.rest_centers;
  const int moved = int(p.model.size() / 2);
  const Vec3d d{0.0, 0.01, 0.0};
  centres[std::size_t(moved)] += d;
  std::vector<Vec3d> out(mesh.vertices.size());
  skinSurfaceCpu(arr.view(), centres.data(), static_cast<const Mat3d*>(nullptr), out.data());
  for (int v = 0; v < b.vertexCount(); ++v) {
    double w = 0.0;
    for (int j = 0; j < b.k; ++j)
      if (b.sphere[std::size_t(v * b.k + j)] == moved) w += b.weight[std::size_t(v * b.k + j)];
    EXPECT_LE(norm(out[std::size_t(v)] - (mesh.vertices[std::size_t(v)] + d * w)), 1e-14);
  }
}

TEST(SkinBinding, BadInput) {
  const PackedOrgan& p = liverPack();
  EXPECT_THROW(bindSkin(liverMesh(), p.model, 0), InputError);
  EXPECT_THROW(bindSkin(liverMesh(), p.model, 17), InputError);
  EXPECT_THROW(bindSkin(liverMesh(), MetaballModel{}, 4), InputError);
  TriangleMesh bad = liverMesh();
  bad.triangles[0][0] = -1;
  EXPECT_THROW(bindSkin(bad, p.model, 4), InputError);
  MetaballModel zero = p.model;
  zero.rest_radii[3] = 0.0;
  EXPECT_THROW(bindSkin(liverMesh(), zero, 4), InputError);
}

// The falloff w = (1 - e / rho)^2 against hand-computed weights: a vertex at the origin and four spheres of radius
// 1 cm on the x axis at 5, 7, 10 and 16 cm have surface distances d = 4, 6, 9 and 15 cm; k = 3 binds the first three
// with e = d - 4 cm = 0, 2, 5 cm, and the fourth (unbound) sets rho = 11 cm. Raw weights 1, (9/11)^2, (6/11)^2, i.e.
// 121 : 81 : 36 over 238 once normalised (a linear falloff would give 11 : 9 : 6 over 26).
TEST(SkinBinding, WeightsFallOffAsTheSquareOfTheDistanceMargin) {
  EXPECT_EQ(skin::bindWeight(0.0, 0.11), 1.0);
  EXPECT_NEAR(skin::bindWeight(0.25, 1.0), 0.5625, 1e-15);
  EXPECT_NEAR(skin::bindWeight(0.75, 1.0), 0.0625, 1e-15);
  EXPECT_EQ(skin::bindWeight(1.0, 1.0), 0.0);
  EXPECT_EQ(skin::bindWeight(1.5, 1.0), 0.0);  // beyond the first unbound sphere: nothing
  EXPECT_EQ(skin::bindWeight(0.3, 0.0), 1.0);  // all candidates equally near: equal weights after normalisation

  MetaballModel line;
  line.rest_centers = {{0.05, 0, 0}, {0.07, 0, 0}, {0.10, 0, 0}, {0.16, 0, 0}};
  line.rest_radii = {0.01, 0.01, 0.01, 0.01};
  line.masses = {1, 1, 1, 1};
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {0, 0.001, 0}, {0, 0, 0.001}};
  mesh.triangles = {{0, 1, 2}};
  const SkinBinding b = bindSkin(mesh, line, 3);
  const double want[3] = {121.0 / 238.0, 81.0 / 238.0, 36.0 / 238.0};
  for (int j = 0; j < 3; ++j) {
    EXPECT_EQ(b.sphere[std::size_t(j)], j);
    EXPECT_NEAR(b.weight[std::size_t(j)], want[j], 1e-12) << "slot " << j;
  }
}

TEST(SkinBinding, FewerSpheresThanSlots) {
  MetaballModel two;
  two.rest_centers = {{-0.01, 0, 0}, {0.01, 0, 0}};
  two.rest_radii = {0.012, 0.012};
  two.masses = {1, 1};
  const TriangleMesh mesh = makeSphereMesh(0.02, 3);
  const SkinBinding b = bindSkin(mesh, two, 4);
  for (int v = 0; v < b.vertexCount(); ++v) {
    double s = 0.0;
    for (int j = 0; j < 4; ++j) s += b.weight[std::size_t(v * 4 + j)];
    EXPECT_NEAR(s, 1.0, 1e-14);
    for (int j = 2; j < 4; ++j) EXPECT_EQ(b.weight[std::size_t(v * 4 + j)], 0.0);
  }
}

}  // namespace
}  // namespace inc

namespace inc {
namespace {

TEST(SphereRotations, QuaternionsConvertToTheSameRotations) {
  std::vector<pbd::Quat<double>> q = {pbd::quatFromAxisAngle(Vec3d{0.0, 0.0, 1.0}, 0.5),
                                      pbd::quatFromAxisAngle(Vec3d{0.6, 0.0, 0.8}, -1.2), pbd::Quat<double>{}};
  std::vector<Mat3d> m(q.size());
  cpu::quatsToMatricesCpu(int(q.size()), q.data(), m.data());
  EXPECT_LE(frobeniusNorm(m[0] - rotation({0.0, 0.0, 1.0}, 0.5)), 1e-15);
  EXPECT_LE(frobeniusNorm(m[1] - rotation({0.6, 0.0, 0.8}, -1.2)), 1e-15);
  EXPECT_LE(frobeniusNorm(m[2] - Mat3d::identity()), 0.0);
}

TEST(SphereRotations, RigidMotionRecoveredExactly) {
  const PackedOrgan& p = liverPack();
  const auto nb = sphereNeighbourhoods<double>(p.model);
  const Mat3d R = rotation({1.0, 2.0, -0.5}, 1.1);
  const Vec3d t{0.02, 0.0, -0.04};
  std::vector<Vec3d> x;
  for (const auto& c : p.model.rest_centers) x.push_back(R * c + t);
  const int n = int(p.model.size());
  std::vector<pbd::Quat<double>> q(static_cast<std::size_t>(n));
  std::vector<Mat3d> rots(static_cast<std::size_t>(n));
  // A cold start from the identity converges linearly (slowly for flat neighbourhoods); frames warm-start.
  cpu::sphereRotationsCpu(n, x.data(), nb.rest_centres.data(), nb.masses.data(), nb.offsets.data(),
                          nb.neighbours.data(), 300, q.data(), rots.data());
  for (int i = 0; i < n; ++i) EXPECT_LE(frobeniusNorm(rots[std::size_t(i)] - R), 1e-9) << "sphere " << i;
  // Warm start: one more iteration from the converged quaternions changes nothing.
  std::vector<Mat3d> again(rots);
  cpu::sphereRotationsCpu(n, x.data(), nb.rest_centres.data(), nb.masses.data(), nb.offsets.data(),
                          nb.neighbours.data(), 1, q.data(), again.data());
  for (int i = 0; i < n; ++i) EXPECT_LE(frobeniusNorm(again[std::size_t(i)] - R), 1e-9);
}

// Twist of a bar about its long axis, theta(x) = (pi / 2) x / L: with per-sphere rotations the skin follows the
// exact map x -> Rot_x(theta(x)) x much more closely and keeps its volume; translation-only blending shrinks it.
TEST(SphereRotations, TwistDoesNotShrinkTheSkin) {
  const double L = 0.2, a = 0.03;
  const TriangleMesh bar = makeBoxMesh({L / 2, a, a}, 12);
  PackingOptions o;
  o.target_spheres = 150;
  o.samples = 6000;
  const PackedOrgan p = packOrgan(bar, o);
  const SkinArrays<double> arr = skinArrays<double>(bindSkin(bar, p.model, 4));
  const auto nb = sphereNeighbourhoods<double>(p.model);
  const double kPi = 3.14159265358979323846;
  auto twistMap = [&](const Vec3d& v) {
    const double th = 0.5 * kPi * v.x / L, c = std::cos(th), s = std::sin(th);
    return Vec3d{v.x, c * v.y - s * v.z, s * v.y + c * v.z};
  };
  std::vector<Vec3d> x;
  for (const auto& c : p.model.rest_centers) x.push_back(twistMap(c));
  const int n = int(p.model.size());
  std::vector<pbd::Quat<double>> q(static_cast<std::size_t>(n));
  std::vector<Mat3d> rots(static_cast<std::size_t>(n));
  cpu::sphereRotationsCpu(n, x.data(), nb.rest_centres.data(), nb.masses.data(), nb.offsets.data(),
                          nb.neighbours.data(), 20, q.data(), rots.data());
  std::vector<Vec3d> with(bar.vertices.size()), without(bar.vertices.size());
  cpu::skinSurfaceCpu(arr.view(), x.data(), rots.data(), with.data());
  cpu::skinSurfaceCpu(arr.view(), x.data(), static_cast<const Mat3d*>(nullptr), without.data());
  double err_with = 0.0, err_without = 0.0;
  for (std::size_t v = 0; v < with.size(); ++v) {
    err_with += norm(with[v] - twistMap(bar.vertices[v]));
    err_without += norm(without[v] - twistMap(bar.vertices[v]));
  }
  err_with /= double(with.size());
  err_without /= double(with.size());
  TriangleMesh mw = bar, mo = bar;
  mw.vertices = with;
  mo.vertices = without;
  const double v0 = analyzeMesh(bar).signed_volume;
  const double dv_with = analyzeMesh(mw).signed_volume / v0 - 1.0,
               dv_without = analyzeMesh(mo).signed_volume / v0 - 1.0;
  std::printf("twist: mean error with rotations %.3e m, translation only %.3e m; volume change %.4f vs %.4f\n",
              err_with, err_without, dv_with, dv_without);
  EXPECT_LT(err_with, 0.5 * err_without);
  EXPECT_LT(std::fabs(dv_with), 0.02);
  EXPECT_LT(std::fabs(dv_with), std::fabs(dv_without));
}

}  // namespace
}  // namespace inc
