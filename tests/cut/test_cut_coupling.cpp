// Coupling math (eqs. 11-13, physics/cut_coupling.h) and the MLS solver's coupling groups: gradients, an analytic
// oscillator.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "host/backends/solver_factory.h"
#include "model/input_error.h"
#include "model/mls_solver.h"
#include "physics/cut_coupling.h"
#include "tests/support/mls_test_scenes.h"

namespace inc {
namespace {

using mls_test::hashSigned;

// E of one group: the springs' Hooke energies at x_a = C_a + mean(u) (eqs. 11 and 13).
double groupEnergy(const std::vector<Vec3d>& u, const Vec3d& c, const std::vector<Vec3d>& anchors,
                   const std::vector<double>& rest, const std::vector<double>& k) {
  std::vector<std::int32_t> members(u.size());
  for (std::size_t i = 0; i < u.size(); ++i) members[i] = std::int32_t(i);
  const Vec3d xa = c + couplingSphereDisplacement(u.data(), members.data(), 0, std::int32_t(u.size()));
  double e = 0.0;
  for (std::size_t s = 0; s < anchors.size(); ++s) e += couplingSpringEnergy(xa, anchors[s], rest[s], k[s]);
  return e;
}

// The spring force is -dE/dx_a of k/2 (|x_a - x_j| - l)^2: central differences agree to 1e-7 of its size.
TEST(CouplingMath, SpringForceIsTheNegativeEnergyGradient) {
  for (int t = 0; t < 20; ++t) {
    const Vec3d xa(0.01 * hashSigned(3 * t), 0.01 * hashSigned(3 * t + 1), 0.01 * hashSigned(3 * t + 2));
    const Vec3d xj(0.012 + 0.003 * hashSigned(100 + t), 0.004 * hashSigned(200 + t), 0.002 * hashSigned(300 + t));
    const double l = 0.01 + 0.005 * hashSigned(400 + t), k = 50.0 + 20.0 * hashSigned(500 + t);
    const Vec3d f = couplingSpringForce(xa, xj, l, k);
    const double h = 1e-7;
    for (int c = 0; c < 3; ++c) {
      Vec3d p = xa, m = xa;
      p[c] += h;
      m[c] -= h;
      const double g = (couplingSpringEnergy(p, xj, l, k) - couplingSpringEnergy(m, xj, l, k)) / (2 * h);
      EXPECT_NEAR(f[c], -g, 1e-7 * (norm(f) + 1e-12)) << "case " << t << " component " << c;
    }
  }
  EXPECT_EQ(norm(couplingSpringForce(Vec3d(1, 2, 3), Vec3d(1, 2, 3), 0.01, 10.0)), 0.0);  // coincident ends
}

// One coupling group for the tests below: n points in a lens off the sphere centre C (as the points a cut leaves in
// an interface sphere are), three springs, and the rest frames mlsCouplingFrames derives. view(false): the same
// group without rest frames (the plain mean of eq. 13).
struct RotatingGroup {
  int n = 12;
  std::vector<Vec3d> rest, anchors;
  Vec3d centre{0.001, -0.002, 0.0005};
  std::vector<double> lengths{0.01, 0.0105, 0.0095}, k{80.0, 120.0, 60.0};
  std::vector<std::int32_t> offsets, members, soff{0, 3};
  MlsCouplingFrames frames;
  Vec3d disp, share;
  Mat3d torque;
  pbd::Quat<double> rot;
  explicit RotatingGroup(int count = 12) : n(count), offsets{0, count} {
    for (int i = 0; i < n; ++i) {
      rest.push_back(centre +
                     Vec3d(0.003 + 0.002 * hashSigned(i), 0.003 * hashSigned(30 + i), 0.0025 * hashSigned(60 + i)));
      members.push_back(i);
    }
    anchors = {centre + Vec3d(0.012, 0.0, 0.0), centre + Vec3d(0.0, -0.011, 0.002),
               centre + Vec3d(-0.004, 0.003, 0.01)};
    MlsCouplingGroups g;
    g.members = members;
    g.member_offsets = offsets;
    g.rest_centres = {centre};
    g.spring_offsets = soff;
    g.rest_lengths = lengths;
    g.stiffnesses = k;
    frames = mlsCouplingFrames(g, rest);
  }
  CouplingView<double> view(bool rotating = true) {
    CouplingView<double> v;
    v.groups = 1;
    v.member_offsets = offsets.data();
    v.members = members.data();
    v.rest_centre = &centre;
    v.spring_offsets = soff.data();
    v.anchor = anchors.data();
    v.rest_length = lengths.data();
    v.stiffness = k.data();
    v.group_displacement = &disp;
    v.member_force = &share;
    if (!rotating) return v;
    v.member_rest = rest.data();
    v.rest_centroid = frames.centroid.data();
    v.rest_gram = frames.gram.data();
    v.inertia_inverse = frames.inertia_inverse.data();
    v.rotation = &rot;
    v.member_torque = &torque;
    return v;
  }
  // u_a (fresh warm start: a converged extraction of the rotation at u).
  Vec3d displacement(const std::vector<Vec3d>& u) {
    rot = pbd::Quat<double>();
    couplingGroupPass(view(), u.data(), 0);
    return disp;
  }
  double energy(const std::vector<Vec3d>& u) {
    const Vec3d xa = centre + displacement(u);
    double e = 0.0;
    for (std::size_t s = 0; s < anchors.size(); ++s) e += couplingSpringEnergy(xa, anchors[s], lengths[s], k[s]);
    return e;
  }
  Vec3d memberForce(int i) const {
    return couplingMemberForce(share, &torque, frames.centroid.data(), rest[std::size_t(i)], 0);
  }
};

// eq. 12 as the chain rule of eq. 13: the force share on each overlapping point is -dE/du_i of the group's
// spring energy with x_a = C_a + mean(u) (central differences, 1e-6 of the share).
TEST(CouplingMath, GroupShareIsTheGradientWithRespectToEachMember) {
  const int n = 7;
  std::vector<Vec3d> u(n);
  for (int i = 0; i < n; ++i) u[i] = Vec3d(hashSigned(i), hashSigned(10 + i), hashSigned(20 + i)) * 0.002;
  RotatingGroup grp(n);
  const Vec3d c = grp.centre;
  const std::vector<Vec3d> anchors = grp.anchors;
  const std::vector<double> rest = grp.lengths, k = grp.k;
  const Vec3d& disp = grp.disp;
  const Vec3d& share = grp.share;
  CouplingView<double> view = grp.view(false);
  couplingGroupPass(view, u.data(), 0);
  // eq. 13: the mean displacement.
  Vec3d mean;
  for (const auto& v : u) mean += v * (1.0 / n);
  EXPECT_LT(norm(disp - mean), 1e-18);
  const double h = 1e-8;
  for (int i = 0; i < n; ++i)
    for (int comp = 0; comp < 3; ++comp) {
      std::vector<Vec3d> p = u, m = u;
      p[i][comp] += h;
      m[i][comp] -= h;
      const double g = (groupEnergy(p, c, anchors, rest, k) - groupEnergy(m, c, anchors, rest, k)) / (2 * h);
      EXPECT_NEAR(share[comp], -g, 1e-6 * norm(share)) << "member " << i << " component " << comp;
    }
  // A group with no spring feels nothing.
  std::vector<std::int32_t> none{0, 0};
  view.spring_offsets = none.data();
  couplingGroupPass(view, u.data(), 0);
  EXPECT_EQ(norm(share), 0.0);
}

std::vector<Vec3d> rigidDisplacements(const std::vector<Vec3d>& rest, const Mat3d& r, const Vec3d& t) {
  std::vector<Vec3d> u;
  for (const Vec3d& x : rest) u.push_back(r * x + t - x);
  return u;
}

// The paper's eq. 13 (the mean displacement) misplaces a turned sphere by (R - I)(Xbar - C); the rotation-aware
// eq. 13 puts it at R C + t for any rigid motion of its points (1e-12 m), and stays the plain mean under a
// translation (bit for bit) and at rest (exactly zero).
TEST(CouplingMath, RotatingGroupFollowsAnyRigidMotionExactly) {
  RotatingGroup grp;
  ASSERT_GT(grp.frames.min_inertia[0], 0.0);  // the lens spans a volume: the group rotates
  EXPECT_EQ(norm(grp.displacement(std::vector<Vec3d>(grp.rest.size()))), 0.0);
  const Vec3d t(0.004, -0.002, 0.003);
  const std::vector<Vec3d> shifted = rigidDisplacements(grp.rest, Mat3d::identity(), t);
  const Vec3d ut = grp.displacement(shifted);
  const Vec3d mean = couplingSphereDisplacement(shifted.data(), grp.members.data(), 0, grp.n);
  EXPECT_EQ(ut.x, mean.x);
  EXPECT_EQ(ut.y, mean.y);
  EXPECT_EQ(ut.z, mean.z);
  for (double angle : {0.1, 0.7, 1.5, 2.5, 3.0}) {
    const Mat3d r = mls_test::rotation(Vec3d(0.3, -1.0, 0.5), angle);
    const Vec3d ua = grp.displacement(rigidDisplacements(grp.rest, r, t));
    EXPECT_LT(norm(grp.centre + ua - (r * grp.centre + t)), 1e-12) << "angle " << angle;
    const Vec3d old =
        couplingSphereDisplacement(rigidDisplacements(grp.rest, r, t).data(), grp.members.data(), 0, grp.n);
    EXPECT_GT(norm(grp.centre + old - (r * grp.centre + t)), 1e-4) << "the plain mean is off by (R - I)(Xbar - C)";
  }
}

// The rotation-aware eq. 12: at a rigid configuration the members' forces are -dE/du_i of the springs' energy with
// x_a(u) the rotation-aware eq. 13 (central differences, 1e-5 of the largest force), and together they carry the
// springs' force F_a and its moment about the centroid, (x_a - xbar) x F_a (1e-12 relative).
TEST(CouplingMath, RotatingGroupSharesAreTheGradientAndCarryForceAndMoment) {
  RotatingGroup grp;
  const Mat3d r = mls_test::rotation(Vec3d(1.0, 0.2, -0.4), 0.6);
  const std::vector<Vec3d> u = rigidDisplacements(grp.rest, r, Vec3d(0.002, 0.001, -0.003));
  const Vec3d ua = grp.displacement(u);
  std::vector<Vec3d> f(std::size_t(grp.n));
  Vec3d total, moment, xbar;
  for (int i = 0; i < grp.n; ++i) xbar += (grp.rest[std::size_t(i)] + u[std::size_t(i)]) * (1.0 / grp.n);
  double fmax = 0.0;
  for (int i = 0; i < grp.n; ++i) {
    f[std::size_t(i)] = grp.memberForce(i);
    total += f[std::size_t(i)];
    moment += cross(grp.rest[std::size_t(i)] + u[std::size_t(i)] - xbar, f[std::size_t(i)]);
    fmax = std::max(fmax, norm(f[std::size_t(i)]));
  }
  const Vec3d fa = grp.share * double(grp.n), xa = grp.centre + ua;
  EXPECT_LT(norm(total - fa), 1e-12 * norm(fa));
  EXPECT_LT(norm(moment - cross(xa - xbar, fa)), 1e-12 * norm(fa) * norm(xa - xbar));
  EXPECT_GT(norm(cross(xa - xbar, fa)), 0.1 * norm(fa) * 0.001);  // a real moment, not a centred sphere
  const double h = 1e-8;
  for (int i = 0; i < grp.n; ++i)
    for (int comp = 0; comp < 3; ++comp) {
      std::vector<Vec3d> p = u, m = u;
      p[std::size_t(i)][comp] += h;
      m[std::size_t(i)][comp] -= h;
      const double g = (grp.energy(p) - grp.energy(m)) / (2 * h);
      EXPECT_NEAR(f[std::size_t(i)][comp], -g, 1e-5 * fmax) << "member " << i << " component " << comp;
    }
}

// Points too few or along a line determine no rotation: the group follows the plain mean, and the stable step
// is the translation limit alone; a rotating group's moment arm shortens the step (sum k |C - Xbar|^2 / (m J)).
TEST(CouplingMath, DegenerateGroupsFollowThePlainMean) {
  MlsCouplingGroups g;
  std::vector<Vec3d> rest;
  for (int i = 0; i < 6; ++i) rest.push_back(Vec3d(0.001 * i, 0.0, 1e-9 * hashSigned(i)));  // a line
  for (int i = 0; i < 3; ++i) rest.push_back(Vec3d(0.0, 0.001 * i, 0.002));                 // three points
  g.members = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  g.member_offsets = {0, 6, 9};
  g.rest_centres = {Vec3d(0.0, 0.003, 0.0), Vec3d(0.002, 0.0, 0.002)};
  g.spring_offsets = {0, 1, 2};
  g.rest_lengths = {0.01, 0.01};
  g.stiffnesses = {10.0, 10.0};
  const MlsCouplingFrames fr = mlsCouplingFrames(g, rest);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(fr.min_inertia[std::size_t(k)], 0.0) << k;
    EXPECT_EQ(trace(fr.inertia_inverse[std::size_t(k)]), 0.0) << k;
  }
  const std::vector<double> mass(9, 0.001);
  EXPECT_EQ(mlsCouplingStableStep(g, mass, &fr), mlsCouplingStableStep(g, mass));
  RotatingGroup grp;
  MlsCouplingGroups one;
  one.members = grp.members;
  one.member_offsets = grp.offsets;
  one.rest_centres = {grp.centre};
  one.spring_offsets = grp.soff;
  one.rest_lengths = grp.lengths;
  one.stiffnesses = grp.k;
  const std::vector<double> m12(12, 0.001);
  const Vec3d arm = grp.centre - grp.frames.centroid[0];
  const double omega_rot = std::sqrt(260.0 * dot(arm, arm) / (0.001 * grp.frames.min_inertia[0]));
  const double omega_trans = std::sqrt(260.0 / 0.012);
  EXPECT_NEAR(mlsCouplingStableStep(one, m12, &grp.frames), 2.0 / std::max(omega_rot, omega_trans), 1e-12);
}

// A 3 x 3 x 3 MLS block, all 27 points one group on one spring (k = 1 N/m) to a fixed anchor, displaced 1 mm
// along the spring, undamped, no gravity: the block moves rigidly and its centre oscillates at omega =
// sqrt(k / M), amplitude kept (leapfrog is symplectic). Period within 0.5 %, amplitude within 1 %.
TEST(MlsCouplingGroups, GroupOnASpringOscillatesAtSqrtKOverM) {
  MlsBuildInput in = mls_test::blockInput(3, 3, 3, 0.005);
  in.material.youngs_modulus_pa = 1.0e3;
  auto solver = makeMlsSolver(in, BackendKind::Cpu, Precision::Float64);
  const std::size_t n = solver->size();
  ASSERT_EQ(n, 27u);
  const std::vector<Vec3d> rest = solver->restPositions();
  Vec3d c;
  for (const auto& x : rest) c += x * (1.0 / double(n));
  MlsCouplingGroups g;
  for (std::size_t i = 0; i < n; ++i) g.members.push_back(std::int32_t(i));
  g.member_offsets = {0, std::int32_t(n)};
  g.rest_centres = {c};
  g.spring_offsets = {0, 1};
  g.rest_lengths = {0.02};
  g.stiffnesses = {1.0};
  const double dt_elastic = solver->stableTimeStep();
  solver->setCouplingGroups(g);
  solver->setCouplingAnchors({c + Vec3d(0.02, 0, 0)});
  const double mass = solver->modelStats().total_mass;
  const double omega = std::sqrt(1.0 / mass);
  // The stable step combines the elastic and the spring limit 2 / omega (exactly, as documented).
  const double dt_spring = 2.0 / omega;
  EXPECT_NEAR(solver->stableTimeStep(),
              1.0 / std::sqrt(1.0 / (dt_elastic * dt_elastic) + 1.0 / (dt_spring * dt_spring)), 1e-12 * dt_elastic);
  solver->setDisplacements(std::vector<Vec3d>(n, Vec3d(0.001, 0, 0)));
  const double dt = 0.5 * solver->stableTimeStep();
  const double period = 2.0 * 3.141592653589793 / omega;
  const int steps = int(std::ceil(2.2 * period / dt));
  std::vector<Vec3d> ua;
  double prev = 0.001, t = 0.0, amp = 0.0;
  std::vector<double> crossings;  // downward zero crossings of the centre's x displacement
  for (int s = 0; s < steps; ++s) {
    solver->step(dt, 1);
    t += dt;
    solver->couplingDisplacements(ua);
    const double x = ua[0].x;
    amp = std::max(amp, std::fabs(x));
    if (prev > 0 && x <= 0) crossings.push_back(t - dt * x / (x - prev));
    prev = x;
  }
  ASSERT_GE(crossings.size(), 2u);
  EXPECT_NEAR((crossings[1] - crossings[0]) / period, 1.0, 5e-3);
  EXPECT_NEAR(amp / 0.001, 1.0, 1e-2);
  // Rigid: every point has the centre's displacement (no elastic deformation from a uniform share).
  std::vector<Vec3d> u;
  solver->displacements(u);
  for (const auto& v : u) EXPECT_LT(norm(v - ua[0]), 1e-9);
}

TEST(MlsCouplingGroups, NewAnchorsRefreshOnlyTheSpringShareBitForBit) {
  // The CPU solver keeps the elastic forces when only the anchors change (a coupling exchange) and adds the new
  // springs' share; stepping on from there must equal stepping after a full recomputation of both passes.
  MlsBuildInput in = mls_test::blockInput(4, 3, 3, 0.005);
  in.material.youngs_modulus_pa = 1.0e3;
  std::unique_ptr<MlsSolver> a = makeMlsSolver(in, BackendKind::Cpu, Precision::Float64);
  std::unique_ptr<MlsSolver> b = makeMlsSolver(in, BackendKind::Cpu, Precision::Float64);
  const std::size_t n = a->size();
  MlsCouplingGroups g;
  for (std::size_t i = 0; i < n / 2; ++i) g.members.push_back(std::int32_t(i));
  g.member_offsets = {0, std::int32_t(n / 2)};
  g.rest_centres = {a->restPositions()[0]};
  g.spring_offsets = {0, 1};
  g.rest_lengths = {0.02};
  g.stiffnesses = {5.0};
  for (MlsSolver* s : {a.get(), b.get()}) {
    s->setCouplingGroups(g);
    s->setCouplingAnchors({g.rest_centres[0] + Vec3d(0.02, 0, 0)});
    s->step(0.5 * s->stableTimeStep(), 10);
    s->setCouplingAnchors({g.rest_centres[0] + Vec3d(0.025, 0.004, 0)});
  }
  b->computeForces();  // both passes again at the same displacement
  for (MlsSolver* s : {a.get(), b.get()}) s->step(0.5 * s->stableTimeStep(), 10);
  std::vector<Vec3d> ua, ub;
  a->displacements(ua);
  b->displacements(ub);
  double moved = 0;
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(ua[i].x, ub[i].x) << i;
    EXPECT_EQ(ua[i].y, ub[i].y) << i;
    EXPECT_EQ(ua[i].z, ub[i].z) << i;
    moved = std::max(moved, norm(ua[i]));
  }
  EXPECT_GT(moved, 0.0);
}

TEST(MlsCouplingGroups, BadGroupsAreInputErrors) {
  auto solver = makeMlsSolver(mls_test::blockInput(3, 3, 3, 0.005), BackendKind::Cpu, Precision::Float64);
  MlsCouplingGroups g;
  g.members = {0, 1, 1};
  g.member_offsets = {0, 2, 3};
  g.rest_centres = {Vec3d(), Vec3d()};
  g.spring_offsets = {0, 0, 0};
  EXPECT_THROW(solver->setCouplingGroups(g), InputError);  // particle 1 in two groups
  g.members = {0, 1, 99};
  EXPECT_THROW(solver->setCouplingGroups(g), InputError);  // out of range
  g.members = {0, 1, 2};
  g.spring_offsets = {0, 1, 1};
  g.rest_lengths = {0.01};
  g.stiffnesses = {-1.0};
  EXPECT_THROW(solver->setCouplingGroups(g), InputError);  // negative stiffness
  g.stiffnesses = {1.0};
  EXPECT_NO_THROW(solver->setCouplingGroups(g));
  EXPECT_THROW(solver->setCouplingAnchors({}), std::exception);  // one anchor per spring
}

}  // namespace
}  // namespace inc
