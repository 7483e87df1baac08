// Tests of the boundary-element global model: sphere under pressure, SMW update == fresh solve, interior points.
#include <gtest/gtest.h>

#include <cstdio>

#include "host/haptics/bem_global.h"
#include "model/input_error.h"
#include "test_paths.h"

namespace inc {
namespace {

TEST(HapticBem, SphereUnderUniformPressure) {
  const double R = 0.05, E = 5e3, nu = 0.3, p = 100.0;
  BemModel m(icosphereMesh(R, 2), {E, nu});  // 320 elements
  const int n = m.elementCount();
  Eigen::VectorXd t(3 * n);
  for (int j = 0; j < n; ++j)
    t.segment<3>(3 * j) << -p * m.normals()[j].x, -p * m.normals()[j].y, -p * m.normals()[j].z;
  const Eigen::VectorXd u = m.solveTractionProblem(t);
  // Exact for any shape under uniform pressure: u = -p (1 - 2 nu) / E x, so u_r = -p R (1 - 2 nu) / E.
  double worst = 0.0, mean = 0.0;
  for (int j = 0; j < n; ++j) {
    const Vec3d x = m.centroids()[j];
    const double ur = (u[3 * j] * x.x + u[3 * j + 1] * x.y + u[3 * j + 2] * x.z) / norm(x);
    const double exact = -p * norm(x) * (1.0 - 2.0 * nu) / E;
    worst = std::max(worst, std::fabs(ur / exact - 1.0));
    mean += ur / exact / n;
  }
  std::printf("sphere pressure: mean u_r/exact %.4f, worst deviation %.4f\n", mean, worst);
  EXPECT_LT(worst, 0.05);
}

TEST(HapticBem, SmwUpdateEqualsFreshSolve) {
  const double R = 0.04;
  BemModel m(icosphereMesh(R, 1), {3e3, 0.45});  // 80 elements
  const int n = m.elementCount();
  std::vector<BemBc> base(n, BemBc::kTraction);
  std::vector<int> top;
  for (int j = 0; j < n; ++j) {
    if (m.centroids()[j].z < -0.7 * R) base[j] = BemBc::kDisplacement;  // held at the bottom
    if (m.centroids()[j].z > 0.6 * R) top.push_back(j);
  }
  m.factorBase(base);
  ASSERT_GE(top.size(), 3u);
  for (std::size_t k = 1; k <= top.size(); k += 2) {
    std::vector<int> contact(top.begin(), top.begin() + std::ptrdiff_t(k));
    m.setContact(contact);
    Eigen::VectorXd known = Eigen::VectorXd::Zero(3 * n);
    for (int j : contact) known.segment<3>(3 * j) << 1e-4, 0.0, -2e-3;  // pressed down and sideways
    const Eigen::VectorXd a = m.solve(known), b = m.solveFresh(known);
    EXPECT_LT((a - b).norm() / b.norm(), 1e-8) << "rank " << 3 * k;
    // Several load cases at once give the columns' answers (the hybrid model's three unit loads).
    Eigen::MatrixXd many(3 * n, 2);
    many.col(0) = known;
    many.col(1) = known * -0.5;
    for (int j = 0; j < n; ++j)
      if (base[j] == BemBc::kTraction && j % 3 == 0) many(3 * j, 1) = 10.0;  // a traction load elsewhere too
    const Eigen::MatrixXd ys = m.solve(many);
    EXPECT_LT((ys.col(0) - a).norm(), 1e-12 * a.norm());
    EXPECT_LT((ys.col(1) - m.solve(Eigen::VectorXd(many.col(1)))).norm(), 1e-12 * ys.col(1).norm());
    // Pressing down: the contact tractions push down on average (the tool does positive work).
    double fz = 0.0;
    for (int j : contact) fz += a[3 * j + 2] * m.areas()[j];
    EXPECT_LT(fz, 0.0);
  }
}

TEST(HapticBem, InteriorDisplacementOfRigidTranslation) {
  // Rigid translation with zero traction: Somigliana gives the same translation inside.
  BemModel m(icosphereMesh(0.05, 2), {3e3, 0.3});
  const int n = m.elementCount();
  Eigen::VectorXd u(3 * n), t = Eigen::VectorXd::Zero(3 * n);
  for (int j = 0; j < n; ++j) u.segment<3>(3 * j) << 1e-3, -2e-3, 5e-4;
  for (const Vec3d& xi : {Vec3d{0, 0, 0}, Vec3d{0.02, 0.01, -0.015}}) {
    const Vec3d v = m.interiorDisplacement(xi, u, t);
    EXPECT_NEAR(v.x, 1e-3, 2e-5);
    EXPECT_NEAR(v.y, -2e-3, 4e-5);
    EXPECT_NEAR(v.z, 5e-4, 1e-5);
  }
}

TEST(HapticBem, BadInputIsInputError) {
  TriangleMesh bad = icosphereMesh(0.01, 0);
  bad.triangles[3] = {0, 0, 1};
  EXPECT_THROW(BemModel(bad, {1e3, 0.3}), InputError);
  EXPECT_THROW(BemModel(icosphereMesh(0.01, 0), {1e3, 0.5}), InputError);
  BemModel m(icosphereMesh(0.01, 0), {1e3, 0.3});
  EXPECT_THROW(m.setContact({1}), InputError);  // before factorBase
  std::vector<BemBc> base(m.elementCount(), BemBc::kTraction);
  base[0] = BemBc::kDisplacement;
  m.factorBase(base);
  EXPECT_THROW(m.setContact({m.elementCount()}), InputError);
}

}  // namespace
}  // namespace inc
