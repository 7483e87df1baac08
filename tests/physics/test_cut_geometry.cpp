// Swept surface vs analytic: sphere hits, segment crossings and sides against the square z = 0, |x|, |y| <= 1.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "host/cut/cut_swept_surface.h"
#include "model/input_error.h"
#include "physics/cut_geometry.h"
#include "tests/support/cut_fixtures.h"

namespace inc {
namespace {

// The swept square: blade from (x, -1, 0) to (x, 1, 0), x from -1 to 1; normal = motion x blade = +z.
SweptSurface square() { return cuttest::straightSweep(-1.0, 1.0, -1.0, 1.0, 5); }

double distanceToSquare(const Vec3d& p) {
  const double dx = std::max(std::fabs(p.x) - 1.0, 0.0), dy = std::max(std::fabs(p.y) - 1.0, 0.0);
  return std::sqrt(dx * dx + dy * dy + p.z * p.z);
}

TEST(CutGeometry, SphereHitsMatchAnalyticDistanceToTheSweptSquare) {
  const SweptSurface s = square();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.6, 1.6), ur(0.01, 0.8);
  std::vector<Vec3d> c;
  std::vector<double> r;
  for (int i = 0; i < 3000; ++i) {
    c.push_back({u(rng), u(rng), 0.5 * u(rng)});
    r.push_back(ur(rng));
  }
  const auto hits = findCutSpheres(s, c, r);
  std::vector<char> hit(c.size(), 0);
  for (auto i : hits) hit[i] = 1;
  int checked = 0, positives = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const double d = distanceToSquare(c[i]);
    if (std::fabs(d - r[i]) < 1e-9) continue;  // on the boundary: either answer is right
    EXPECT_EQ(bool(hit[i]), d < r[i]) << "sphere " << i << " d=" << d << " r=" << r[i];
    ++checked;
    positives += d < r[i];
  }
  EXPECT_GT(checked, 2900);
  EXPECT_GT(positives, 300);  // both outcomes are exercised
  EXPECT_LT(positives, 2700);
}

TEST(CutGeometry, SegmentCrossingAndSideMatchAnalytic) {
  const SweptSurface s = square();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  int crossings = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3d p(u(rng), u(rng), 0.4 * u(rng)), q(u(rng), u(rng), 0.4 * u(rng));
    if (std::fabs(p.z) < 1e-6 || std::fabs(q.z) < 1e-6) continue;
    bool expect = false;
    if ((p.z > 0) != (q.z > 0)) {
      const double t = p.z / (p.z - q.z);
      const Vec3d x = p + (q - p) * t;
      if (std::fabs(std::fabs(x.x) - 1.0) < 1e-9 || std::fabs(std::fabs(x.y) - 1.0) < 1e-9) continue;
      expect = std::fabs(x.x) < 1.0 && std::fabs(x.y) < 1.0;
    }
    EXPECT_EQ(segmentCrossesSweptSurface(s, p, q), expect) << i;
    crossings += expect;
    if (std::fabs(p.x) < 1.0 && std::fabs(p.y) < 1.0) {
      EXPECT_EQ(sideOfSweptSurface(s, p), p.z > 0 ? 1 : -1);
    }
  }
  EXPECT_GT(crossings, 200);
}

// cut::segmentCrossesTriangle itself, on the CPU (the CUDA path calls it directly; the CPU's swept-surface query
// pre-filters by side first, which would hide a segment read as a ray). Triangle (0,0,0), (1,0,0), (0,1,0) in
// z = 0: the closed segment crosses only when its ends lie on both sides of (or on) the plane over the triangle.
TEST(CutGeometry, SegmentCrossesTriangleOnlyBetweenItsEnds) {
  const Vec3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  struct Case {
    const char* what;
    Vec3d p, q;
    bool crosses;
  };
  const Case cases[] = {
      {"passes through", {0.2, 0.2, 1.0}, {0.2, 0.2, -1.0}, true},
      {"slanted, passes through", {-0.5, 0.25, 0.5}, {1.5, 0.25, -0.5}, true},
      {"ends on the triangle", {0.2, 0.2, 1.0}, {0.2, 0.2, 0.0}, true},
      {"starts on the triangle", {0.2, 0.2, 0.0}, {0.2, 0.2, -1.0}, true},
      {"stops short above", {0.2, 0.2, 1.0}, {0.2, 0.2, 0.1}, false},
      {"slanted, stops short", {-0.5, 0.25, 0.5}, {0.3, 0.25, 0.1}, false},
      {"starts beyond, below", {0.2, 0.2, -0.1}, {0.2, 0.2, -1.0}, false},
      {"passes beside", {0.8, 0.8, 1.0}, {0.8, 0.8, -1.0}, false},
      {"lies in the plane", {-0.5, 0.2, 0.0}, {1.5, 0.2, 0.0}, false},
  };
  for (const Case& k : cases) {
    EXPECT_EQ(cut::segmentCrossesTriangle(k.p, k.q, a, b, c), k.crosses) << k.what;
    EXPECT_EQ(cut::segmentCrossesTriangle(k.q, k.p, a, b, c), k.crosses) << k.what << ", reversed";
    EXPECT_EQ(cut::segmentCrossesTriangle(k.p, k.q, a, c, b), k.crosses) << k.what << ", other winding";
  }
}

TEST(CutGeometry, BadBladeIsAnInputError) {
  EXPECT_THROW(sweepSurface({{Vec3d(0, 0, 0), Vec3d(0, 1, 0)}}), InputError);
  EXPECT_THROW(sweepSurface({{Vec3d(0, 0, 0), Vec3d(0, 0, 0)}, {Vec3d(1, 0, 0), Vec3d(1, 1, 0)}}), InputError);
  EXPECT_THROW(sweepSurface({{Vec3d(0, 0, 0), Vec3d(0, 1, 0)}, {Vec3d(NAN, 0, 0), Vec3d(1, 1, 0)}}), InputError);
}

TEST(CutGeometry, IncrementalSweepEqualsBatchSweep) {
  std::vector<BladePose> poses;
  for (int k = 0; k < 6; ++k) {
    const double a = 0.3 * k;  // a curved path
    poses.push_back({Vec3d(std::cos(a), std::sin(a), -0.5), Vec3d(std::cos(a), std::sin(a), 0.5)});
  }
  const SweptSurface batch = sweepSurface(poses);
  SweptSurface inc = sweepSurface({poses[0], poses[1]});
  for (std::size_t k = 2; k < poses.size(); ++k) extendSweptSurface(inc, poses[k]);
  ASSERT_EQ(batch.triangles.size(), inc.triangles.size());
  EXPECT_EQ(batch.triangles.size(), 10u);
  for (std::size_t i = 0; i < batch.vertices.size(); ++i) EXPECT_EQ(norm(batch.vertices[i] - inc.vertices[i]), 0.0);
}

// The pruned query (runs of triangles skipped by their boxes) must give the brute-force scan's triangle and
// distance bit for bit, near the strip and far from it, for a curved strip of many runs.
TEST(CutGeometry, QueryClosestTriangleEqualsTheBruteForceScan) {
  std::vector<BladePose> poses;
  for (int k = 0; k < 40; ++k) {
    const double a = 0.08 * k;
    poses.push_back({Vec3d(0.1 * std::cos(a), 0.1 * std::sin(a), -0.03 + 0.001 * k),
                     Vec3d(0.1 * std::cos(a), 0.1 * std::sin(a), 0.03)});
  }
  const SweptSurface s = sweepSurface(poses);
  ASSERT_GT(s.triangles.size(), 60u);
  const SweptSurfaceQuery q(s);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  int near = 0;
  for (int i = 0; i < 4000; ++i) {
    Vec3d p(u(rng), u(rng), 0.4 * u(rng));
    if (i % 4 == 0) p = s.vertices[std::size_t(i) % s.vertices.size()] + Vec3d(1e-4, -2e-4, 1e-4) * u(rng);
    if (i % 97 == 0) p = s.vertices[std::size_t(i) % s.vertices.size()];  // exactly on the strip: ties
    const double brute = distanceToSweptSurface(s, p);
    ASSERT_EQ(q.distance(p), brute) << i;
    Vec3d kq, kb, n;
    ASSERT_TRUE(closestOnSweptSurface(s, p, kb, n));
    ASSERT_GE(q.closestTriangle(p, kq), 0);
    ASSERT_EQ(norm(kq - kb), 0.0) << i;
    near += brute < 0.01;
  }
  EXPECT_GT(near, 800);
  Vec3d k;
  EXPECT_EQ(SweptSurfaceQuery(SweptSurface{}).closestTriangle(Vec3d(), k), -1);
}

}  // namespace
}  // namespace inc
