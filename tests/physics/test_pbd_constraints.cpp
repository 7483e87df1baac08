// Unit tests of the pure PBD/XPBD projections against hand-computed corrections, gradients and restoring behaviour.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "physics/pbd_collision.h"
#include "physics/pbd_constraints.h"
#include "physics/pbd_rotation.h"
#include "physics/pbd_volume.h"

using namespace inc;
using namespace inc::pbd;

namespace {
const double kPi = 3.141592653589793;
void expectVec(const Vec3d& a, const Vec3d& b, double tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}
}  // namespace

TEST(PbdConstraints, DistanceMatchesPaperEq2And3) {
  // m0 = 1, m1 = 1/3 (w0 = 1, w1 = 3); |p0 - p1| = 2, d = 1, C = 1, n = (-1, 0, 0).
  // Eq. 2: dc1 = -m2/(m1+m2) C n = -(1/3)/(4/3) (-1,0,0) = (0.25,0,0); eq. 3: dc2 = m1/(m1+m2) C n = (-0.75,0,0).
  const DistanceCorrection<double> r =
      projectDistance(Vec3d(0, 0, 0), Vec3d(2, 0, 0), 1.0, 3.0, 1.0, xpbdTerm(false, 0.0, 1.0, 0.01), 0.0);
  EXPECT_DOUBLE_EQ(r.c, 1.0);
  expectVec(r.dp0, Vec3d(0.25, 0, 0), 1e-15);
  expectVec(r.dp1, Vec3d(-0.75, 0, 0), 1e-15);
  // Plain PBD with k = 0.5 moves half as far.
  const DistanceCorrection<double> h =
      projectDistance(Vec3d(0, 0, 0), Vec3d(2, 0, 0), 1.0, 3.0, 1.0, xpbdTerm(false, 0.0, 0.5, 0.01), 0.0);
  expectVec(h.dp0, Vec3d(0.125, 0, 0), 1e-15);
}

TEST(PbdConstraints, XpbdDistanceReachesComplianceBalanceInOneLinearStep) {
  // alpha = 0.5, dt = 0.5 -> alpha~ = 2: dlambda = -C / (w0 + w1 + alpha~) = -1/6; then C + alpha~ lambda = 0.
  const XpbdTerm<double> term = xpbdTerm(true, 0.5, 1.0, 0.5);
  EXPECT_DOUBLE_EQ(term.alpha_tilde, 2.0);
  Vec3d p0(0, 0, 0), p1(2, 0, 0);
  const DistanceCorrection<double> r = projectDistance(p0, p1, 1.0, 3.0, 1.0, term, 0.0);
  EXPECT_NEAR(r.dlambda, -1.0 / 6.0, 1e-15);
  expectVec(r.dp0, Vec3d(1.0 / 6.0, 0, 0), 1e-15);
  expectVec(r.dp1, Vec3d(-0.5, 0, 0), 1e-15);
  p0 += r.dp0;
  p1 += r.dp1;
  const double lambda = r.dlambda;
  const DistanceCorrection<double> r2 = projectDistance(p0, p1, 1.0, 3.0, 1.0, term, lambda);
  EXPECT_NEAR(r2.c + term.alpha_tilde * lambda, 0.0, 1e-14);
  EXPECT_NEAR(r2.dlambda, 0.0, 1e-14);
}

TEST(PbdConstraints, DihedralAngleConventionMatchesTrescaAcos) {
  const Vec3d p0(0, 0, 0), p1(1, 0, 0), p2(0.5, 1, 0);
  EXPECT_NEAR(dihedralAngle(p0, p1, p2, Vec3d(0.5, -1, 0)), kPi, 1e-12);        // flat sheet
  EXPECT_NEAR(dihedralAngle(p0, p1, p2, Vec3d(0.5, 0, 1)), 0.5 * kPi, 1e-12);   // folded one way
  EXPECT_NEAR(dihedralAngle(p0, p1, p2, Vec3d(0.5, 0, -1)), 1.5 * kPi, 1e-12);  // folded the other way
  // The paper's acos(n1 . n2) equals min(psi, 2 pi - psi).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int t = 0; t < 50; ++t) {
    const Vec3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng)),
        d(u(rng), u(rng), u(rng));
    const Vec3d e = b - a, n1 = cross(e, c - a), n2 = cross(e, d - a);
    const double paper = std::acos(std::clamp(dot(n1, n2) / (norm(n1) * norm(n2)), -1.0, 1.0));
    const double psi = dihedralAngle(a, b, c, d);
    EXPECT_NEAR(std::min(psi, 2 * kPi - psi), paper, 1e-9);
  }
}

TEST(PbdConstraints, DihedralGradientsMatchFiniteDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int t = 0; t < 30; ++t) {
    Vec3d p[4] = {
        {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}};
    Vec3d g[4];
    ASSERT_TRUE(dihedralGradients(p[0], p[1], p[2], p[3], g));
    const double h = 1e-6;
    for (int k = 0; k < 4; ++k)
      for (int a = 0; a < 3; ++a) {
        Vec3d q[4] = {p[0], p[1], p[2], p[3]};
        q[k][a] += h;
        double fp = dihedralAngle(q[0], q[1], q[2], q[3]);
        q[k][a] -= 2 * h;
        double fm = dihedralAngle(q[0], q[1], q[2], q[3]);
        if (std::fabs(fp - fm) > kPi) continue;  // straddles the fully-folded wrap at 0 / 2 pi
        EXPECT_NEAR(g[k][a], (fp - fm) / (2 * h), 1e-5 * (1 + std::fabs(g[k][a]))) << "vertex " << k << " axis " << a;
      }
  }
}

TEST(PbdConstraints, BendingHandComputedCorrection) {
  // Hinge on the x axis folded to psi = pi/2, rest flat (pi), unit inverse masses, PBD k = 1.
  // g2 = -|e| n1/|n1|^2 = (0,0,-1), g3 = |e| n2/|n2|^2 = (0,-1,0), g0 = g1 = (0, .5, .5); sum w|g|^2 = 3;
  // C = -pi/2 -> dlambda = pi/6; dp_k = g_k pi/6.
  const BendingCorrection<double> r = projectBending(Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0.5, 1, 0), Vec3d(0.5, 0, 1),
                                                     1.0, 1.0, 1.0, 1.0, kPi, xpbdTerm(false, 0.0, 1.0, 0.01), 0.0);
  EXPECT_NEAR(r.c, -0.5 * kPi, 1e-12);
  EXPECT_NEAR(r.dlambda, kPi / 6, 1e-12);
  expectVec(r.dp[2], Vec3d(0, 0, -kPi / 6), 1e-12);
  expectVec(r.dp[3], Vec3d(0, -kPi / 6, 0), 1e-12);
  expectVec(r.dp[0], Vec3d(0, kPi / 12, kPi / 12), 1e-12);
  expectVec(r.dp[1], Vec3d(0, kPi / 12, kPi / 12), 1e-12);
}

TEST(PbdConstraints, BendingHingeOfTwoTrianglesReturnsToRestAngle) {
  // Two triangles, rest angle 2pi/3; start flat and folded the other way; repeated XPBD projections
  // (alpha = 0) reach the rest angle, and the edge's own length is untouched by bending alone to first order.
  for (double start_z : {0.0, -0.8, 0.9}) {
    Vec3d p[4] = {{0, 0, 0}, {1, 0, 0}, {0.4, 1, 0}, {0.6, -1, start_z}};
    const double rest = 2 * kPi / 3;
    double lambda = 0;
    const XpbdTerm<double> term = xpbdTerm(true, 0.0, 1.0, 0.01);
    for (int it = 0; it < 200; ++it) {
      const BendingCorrection<double> r =
          projectBending(p[0], p[1], p[2], p[3], 1.0, 1.0, 1.0, 1.0, rest, term, lambda);
      for (int k = 0; k < 4; ++k) p[k] += r.dp[k];
      lambda += r.dlambda;
    }
    EXPECT_NEAR(dihedralAngle(p[0], p[1], p[2], p[3]), rest, 1e-8) << "start z " << start_z;
    // Fixed hinge edge (w = 0 at p0, p1): the edge stays put.
    Vec3d q[4] = {{0, 0, 0}, {1, 0, 0}, {0.4, 1, 0}, {0.6, -1, start_z}};
    for (int it = 0; it < 200; ++it) {
      const BendingCorrection<double> r = projectBending(q[0], q[1], q[2], q[3], 0.0, 0.0, 1.0, 1.0, rest, term, 0.0);
      for (int k = 0; k < 4; ++k) q[k] += r.dp[k];
    }
    EXPECT_NEAR(dihedralAngle(q[0], q[1], q[2], q[3]), rest, 1e-8);
    expectVec(q[0], Vec3d(0, 0, 0), 0);
    expectVec(q[1], Vec3d(1, 0, 0), 0);
  }
}

TEST(PbdConstraints, TetVolumeHandComputedAndRestores) {
  // Unit corner tet: V = 1/6, rest 1/3, unit w. g1 = (1/6)(1,0,0), g2 = (1/6)(0,1,0), g3 = (1/6)(0,0,1),
  // g0 = -(1/6)(1,1,1); sum |g|^2 = 1/6, C = -1/6 -> dlambda = 1, dp_k = g_k.
  const Vec3d p0(0, 0, 0), p1(1, 0, 0), p2(0, 1, 0), p3(0, 0, 1);
  EXPECT_NEAR(tetSignedVolume(p0, p1, p2, p3), 1.0 / 6, 1e-15);
  const TetVolumeCorrection<double> r =
      projectTetVolume(p0, p1, p2, p3, 1.0, 1.0, 1.0, 1.0, 1.0 / 3, xpbdTerm(false, 0.0, 1.0, 0.01), 0.0);
  EXPECT_NEAR(r.dlambda, 1.0, 1e-14);
  expectVec(r.dp[1], Vec3d(1.0 / 6, 0, 0), 1e-15);
  expectVec(r.dp[0], Vec3d(-1.0 / 6, -1.0 / 6, -1.0 / 6), 1e-15);
  // Squashed tet restores its rest volume under repeated projection.
  Vec3d q[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.3, 0.05}};
  const double v0 = 1.0 / 6;
  for (int it = 0; it < 50; ++it) {
    const TetVolumeCorrection<double> c =
        projectTetVolume(q[0], q[1], q[2], q[3], 1.0, 2.0, 0.5, 1.0, v0, xpbdTerm(true, 0.0, 1.0, 0.01), 0.0);
    for (int k = 0; k < 4; ++k) q[k] += c.dp[k];
  }
  EXPECT_NEAR(tetSignedVolume(q[0], q[1], q[2], q[3]), v0, 1e-12);
}

TEST(PbdConstraints, LaplacianHandComputedCorrection) {
  // Centre at (0.1,0,0), neighbours at (+-1,0,0): delta = (0.1,0,0), rest 0; w = 1; sum w|grad|^2 = 1 + 2/4.
  // dlambda = -(0.1,0,0)/1.5; centre moves by dlambda, each neighbour by -dlambda/2: delta becomes 0.
  Vec3d x[3] = {{0.1, 0, 0}, {1, 0, 0}, {-1, 0, 0}};
  const double w[3] = {1, 1, 1};
  const std::int32_t ids[3] = {0, 1, 2};
  const LaplacianCorrection<double> r =
      projectLaplacian(x, w, ids, 3, Vec3d(), xpbdTerm(false, 0.0, 1.0, 0.01), Vec3d());
  expectVec(r.dlambda, Vec3d(-0.1 / 1.5, 0, 0), 1e-15);
  expectVec(r.d_center, Vec3d(-0.1 / 1.5, 0, 0), 1e-15);
  EXPECT_DOUBLE_EQ(r.inv_n, 0.5);
  x[0] += r.d_center;
  for (int k = 1; k < 3; ++k) x[k] += r.dlambda * (-w[k] * r.inv_n);
  expectVec(x[0] - (x[1] + x[2]) * 0.5, Vec3d(), 1e-15);
}

TEST(PbdConstraints, RotationExtractionRecoversPolarFactor) {
  const Vec3d axis = Vec3d(1, 2, -0.5) * (1.0 / norm(Vec3d(1, 2, -0.5)));
  const Mat3d r = quatToMatrix(quatFromAxisAngle(axis, 2.1));
  const Mat3d s = Mat3d::fromRows({1.3, 0.2, 0.1}, {0.2, 0.7, -0.05}, {0.1, -0.05, 1.1});  // SPD stretch
  const Quat<double> q = extractRotation(r * s, Quat<double>{}, 60);
  const Mat3d got = quatToMatrix(q);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) EXPECT_NEAR(got(a, b), r(a, b), 1e-9);
  // Warm start from the answer: stays.
  const Quat<double> q2 = extractRotation(r * s, q, 2);
  EXPECT_NEAR(std::fabs(q2.w * q.w + q2.x * q.x + q2.y * q.y + q2.z * q.z), 1.0, 1e-12);
}

TEST(PbdConstraints, ShapeMatchingGoalsOfARigidlyMovedClusterAreItsPositions) {
  Vec3d rest[5] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  const double m[5] = {1, 2, 1, 1, 0.5};
  const std::int32_t ids[5] = {0, 1, 2, 3, 4};
  Vec3d cm;
  double ms = 0;
  for (int k = 0; k < 5; ++k) {
    cm += rest[k] * m[k];
    ms += m[k];
  }
  cm *= 1.0 / ms;
  Vec3d q[5], x[5];
  const Mat3d r = quatToMatrix(quatFromAxisAngle(Vec3d(0, 0, 1), 1.0));
  for (int k = 0; k < 5; ++k) {
    q[k] = rest[k] - cm;
    x[k] = r * rest[k] + Vec3d(3, -2, 1);
  }
  const ClusterFrame<double> f = clusterFrame(x, m, ids, q, 5);
  const Quat<double> qr = extractRotation(f.a_pq, Quat<double>{}, 40);
  const Mat3d got = quatToMatrix(qr);
  for (int k = 0; k < 5; ++k) {
    expectVec(got * q[k] + f.x_cm, x[k], 1e-9);
    const GoalCorrection<double> g =
        projectGoal(x[k], 1.0 / m[k], got * q[k] + f.x_cm, xpbdTerm(true, 1e-3, 1.0, 0.01), Vec3d());
    expectVec(g.dp, Vec3d(), 1e-9);
  }
  // A displaced member is pulled to its goal: XPBD with alpha~ = w gives half the way.
  const GoalCorrection<double> g =
      projectGoal(Vec3d(1, 0, 0), 2.0, Vec3d(0, 0, 0), XpbdTerm<double>{2.0, 1.0}, Vec3d());
  expectVec(g.dp, Vec3d(-0.5, 0, 0), 1e-15);
}

TEST(PbdCollision, PlaneBoxCapsuleContacts) {
  const PlaneCollider<double> floor{Vec3d(0, 0, 1), 0.0};
  expectVec(planeContact(Vec3d(1, 2, 0.3), 0.5, floor), Vec3d(0, 0, 0.2), 1e-15);
  expectVec(planeContact(Vec3d(1, 2, 0.6), 0.5, floor), Vec3d(), 0);
  const BoxCollider<double> box{Vec3d(0, 0, 0), Vec3d(1, 1, 1)};
  expectVec(boxContact(Vec3d(1.2, 0.5, 0.5), 0.5, box), Vec3d(0.3, 0, 0), 1e-15);    // outside, near +x face
  expectVec(boxContact(Vec3d(0.5, 0.5, 0.9), 0.25, box), Vec3d(0, 0, 0.35), 1e-15);  // inside, nearest +z face
  expectVec(boxContact(Vec3d(2, 2, 2), 0.25, box), Vec3d(), 0);
  const CapsuleCollider<double> tool{Vec3d(0, 0, 0), Vec3d(0, 0, 2), 0.1};
  expectVec(capsuleContact(Vec3d(0.2, 0, 1), 0.15, tool), Vec3d(0.05, 0, 0), 1e-15);  // side
  expectVec(capsuleContact(Vec3d(0, 0, 2.2), 0.15, tool), Vec3d(0, 0, 0.05), 1e-15);  // end cap
  EXPECT_NEAR(norm(capsuleContact(Vec3d(0, 0, 1), 0.15, tool)), 0.25, 1e-15);         // on the axis
  EXPECT_NEAR(capsuleDistance(Vec3d(0.5, 0, 1), tool), 0.4, 1e-15);
}

TEST(PbdVolume, PowerCellVolumesSplitTheUnionOfTwoSpheres) {
  const int K = 4096;
  std::vector<Vec3d> samples(K);
  for (int k = 0; k < K; ++k) samples[k] = unitBallSample<double>(k, K);
  for (const Vec3d& s : samples) ASSERT_LE(norm(s), 1.0);
  // Isolated sphere: its whole ball.
  const Vec3d c[2] = {{0, 0, 0}, {1.2, 0, 0}};
  const double r[2] = {1.0, 0.8};
  const std::int32_t n0[1] = {1}, n1[1] = {0};
  EXPECT_NEAR(powerCellVolume(c[0], 1.0, c, r, n0, 0, samples.data(), K), 4.0 / 3 * kPi, 1e-12);
  // Two overlapping balls: V0 + V1 = |B0 u B1| = |B0| + |B1| - lens.
  const double d = 1.2, r0 = r[0], r1 = r[1];
  const double lens = kPi * (r0 + r1 - d) * (r0 + r1 - d) *
                      (d * d + 2 * d * r1 - 3 * r1 * r1 + 2 * d * r0 + 6 * r0 * r1 - 3 * r0 * r0) / (12 * d);
  const double uni = 4.0 / 3 * kPi * (r0 * r0 * r0 + r1 * r1 * r1) - lens;
  const double v0 = powerCellVolume(c[0], r0, c, r, n0, 1, samples.data(), K);
  const double v1 = powerCellVolume(c[1], r1, c, r, n1, 1, samples.data(), K);
  EXPECT_NEAR(v0 + v1, uni, 0.01 * uni);
  // The radius solve inverts the volume: the isolated ball needing 1.2^3 of its volume gets radius 1.2.
  const double target = 4.0 / 3 * kPi * 1.2 * 1.2 * 1.2;
  EXPECT_NEAR(radiusForCellVolume(c[0], 1.0, 1.5, target, c, r, n0, 0, samples.data(), K, 30), 1.2, 1e-6);
  EXPECT_DOUBLE_EQ(radiusForCellVolume(c[0], 1.0, 1.1, target, c, r, n0, 0, samples.data(), K, 30), 1.1);  // capped
}
