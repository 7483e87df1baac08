// Tests of the tip contact: the MFS tip stiffness (symmetric, positive, frame-covariant) and the probe on a plane.
#include <gtest/gtest.h>

#include <cmath>

#include "host/haptics/tip_contact.h"
#include "model/input_error.h"

namespace inc {
namespace {

const Material kTissue{3e3, 0.45};

double maxAbs(const TipStiffness& k) {
  double m = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m = std::max(m, std::fabs(k.k_n_per_m[i][j]));
  return m;
}

// The condensed tip stiffness of a linear elastic half-ball is symmetric (Galerkin K is) and positive definite
// (the outer shell is held), and a tilted tissue plane only rotates it: K(n) = R K(z) R^T, so the normal stiffness
// n.K(n).n equals K(z)_zz and the normal and tangential stiffnesses do not depend on the frame (to 1e-9).
TEST(HapticTipContact, TipStiffnessIsSymmetricPositiveAndFrameCovariant) {
  const TipStiffness kz = mfsTipStiffness(kTissue, 0.008, 0.002, Vec3d{0, 0, 1});
  const double scale = maxAbs(kz);
  ASSERT_GT(scale, 0.0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(kz.k_n_per_m[i][j], kz.k_n_per_m[j][i], 1e-9 * scale);
  for (int i = 0; i < 3; ++i) EXPECT_GT(kz.k_n_per_m[i][i], 0.0);
  // Pressing straight in: the tissue pushes the hand back out.
  EXPECT_GT(kz.handForce(Vec3d{0, 0, -1e-3}).z, 0.0);
  const Vec3d n = Vec3d{1, -2, 2} * (1.0 / 3.0);
  const TipStiffness kn = mfsTipStiffness(kTissue, 0.008, 0.002, n);
  const Vec3d fn = kn.handForce(n * -1e-3);
  EXPECT_NEAR(dot(fn, n), kz.handForce(Vec3d{0, 0, -1e-3}).z, 1e-9 * scale * 1e-3);
  // A tangential push: the same tangential stiffness as in the z frame (the half-ball is axisymmetric up to its
  // node rings, so compare the mean of two orthogonal tangents with kz's).
  const Vec3d t1 = Vec3d{2, 2, 1} * (1.0 / 3.0), t2 = cross(n, t1);
  ASSERT_NEAR(dot(t1, n), 0.0, 1e-15);
  const double kt_n = 0.5 * (dot(kn.handForce(t1 * 1e-3), t1) + dot(kn.handForce(t2 * 1e-3), t2));
  const double kt_z = 0.5 * (dot(kz.handForce(Vec3d{1e-3, 0, 0}), Vec3d{1, 0, 0}) +
                             dot(kz.handForce(Vec3d{0, 1e-3, 0}), Vec3d{0, 1, 0}));
  EXPECT_NEAR(kt_n, kt_z, 1e-9 * scale * 1e-3);
  EXPECT_THROW(mfsTipStiffness(kTissue, 0.008, 0.005, Vec3d{0, 0, 1}), InputError);  // fewer than two shells
}

ForceRequest at(const Vec3d& p) {
  ForceRequest q;
  q.dt_s = 1e-3;
  q.sample.position_m = p;
  return q;
}

// The probe: no force above the plane; below it the elastic reaction of the tip's displacement from where it
// entered, linear in the depth; the entry point sticks while the tip slides (a tangential force against the
// slide); leaving and re-entering elsewhere anchors anew.
TEST(HapticTipContact, ProbeAnchorsWhereTheTipEntersTheTissuePlane) {
  const TipStiffness k = mfsTipStiffness(kTissue, 0.008, 0.002, Vec3d{0, 0, 1});
  ProbeTool probe(tipElastic(k), Vec3d{0, 0, 0.01}, Vec3d{0, 0, 1});
  EXPECT_EQ(norm(probe.tick(at({0.001, 0, 0.011})).force_n), 0.0);
  EXPECT_FALSE(probe.inContact());
  const Vec3d f1 = probe.tick(at({0.001, 0, 0.009})).force_n;  // 1 mm in
  EXPECT_TRUE(probe.inContact());
  const double kzz = k.k_n_per_m[2][2];
  EXPECT_NEAR(f1.z, kzz * 1e-3, 1e-12 * kzz);
  const Vec3d f2 = probe.tick(at({0.001, 0, 0.008})).force_n;  // 2 mm in: twice the force
  EXPECT_NEAR(f2.z, 2.0 * f1.z, 1e-12 * kzz);
  const Vec3d f3 = probe.tick(at({0.003, 0, 0.008})).force_n;  // slid 2 mm along +x: pulled back along -x
  EXPECT_LT(f3.x, 0.0);
  EXPECT_EQ(norm(probe.tick(at({0.003, 0, 0.012})).force_n), 0.0);  // out
  const Vec3d f4 = probe.tick(at({0.003, 0, 0.009})).force_n;       // in again, here
  EXPECT_NEAR(f4.z, f1.z, 1e-12 * kzz);
  EXPECT_NEAR(f4.x, f1.x, 1e-12 * kzz);
}

}  // namespace
}  // namespace inc
