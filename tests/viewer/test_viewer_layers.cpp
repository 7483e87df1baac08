// The model layers in a real window (xvfb-run -a with Mesa): impostor spheres against analytic ray casting,
// marked particles in their colours, the translucent swept surface, force arrows along their segments.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "viewer/gl_window.h"
#include "viewer/model_layers.h"
#include "viewer/offscreen_target.h"
#include "viewer/orbit_camera.h"
#include "viewer/screenshot.h"

namespace inc::viewer {
namespace {

constexpr int kW = 160, kH = 120;

class ViewerLayersGl : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    GlWindowOptions opt;
    opt.width = 64;
    opt.height = 64;
    opt.vsync = false;
    window_ = GlWindow::open(opt, &why);
    if (!window_) GTEST_SKIP() << "no display (run under xvfb-run -a): " << why;
  }
  void TearDown() override {
    if (window_) OffscreenTarget::bindDefault(64, 64);
  }
  std::unique_ptr<GlWindow> window_;
};

void clearTarget() {
  glClearColor(0, 0, 0, 1);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

bool lit(const RgbImage& img, int x, int y) {
  const auto* p = img.at(x, y);
  return p[0] + p[1] + p[2] > 0;
}

ViewCamera frontCamera(double dist) {
  return ViewCamera::lookAlong({0, 0, dist}, {0, 0, -1}, {0, 1, 0}, false, 0.3, 0.05, 5.0, kW, kH);
}

// Nearest ray/sphere hit over a set of spheres: the analytic picture the impostors must reproduce.
bool rayCast(const ViewCamera& cam, double px, double py, const std::vector<Vec3d>& c, const std::vector<double>& r,
             Vec3d& hit) {
  Vec3d o, d;
  cam.pixelRay(px, py, o, d);
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Vec3d oc = o - c[i];
    const double b = dot(oc, d), disc = b * b - (dot(oc, oc) - r[i] * r[i]);
    if (disc < 0) continue;
    const double t = -b - std::sqrt(disc);
    if (t > 0 && t < best) best = t;
  }
  if (!std::isfinite(best)) return false;
  hit = o + d * best;
  return true;
}

// One sphere: its analytic screen share (the tangent cone's disc) and the front pole's depth at the centre.
TEST_F(ViewerLayersGl, SphereCoversAnalyticShareAndCentreDepthIsTheFrontPoint) {
  const double R = 0.1, dist = 0.6;
  const ViewCamera cam = frontCamera(dist);
  OffscreenTarget target(kW, kH);
  target.bind();
  clearTarget();
  SphereRenderer spheres;
  spheres.upload({{0, 0, 0}}, {R});
  spheres.draw(cam, ModelLayerColours::sphere);
  const RgbImage img = readFramebuffer(kW, kH);
  std::size_t covered = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) covered += lit(img, x, y) ? 1 : 0;
  const double r_px = std::tan(std::asin(R / dist)) / 0.3 * (kH / 2.0);
  const double expected = M_PI * r_px * r_px;
  EXPECT_NEAR(double(covered), expected, 0.02 * expected);  // 2 %: pixel quantisation of a 33 px radius disc
  const std::vector<float> depth = readDepth(kW / 2, kH / 2, 1, 1);
  Vec3d hit;
  ASSERT_TRUE(pointFromWindowDepth(cam, kW / 2 + 0.5, kH / 2 + 0.5, depth[0], hit));
  // The pixel centre's ray meets the sphere 1/2 px off the pole: z = R within 0.1 mm (24-bit depth ~0.01 mm).
  EXPECT_NEAR(hit.z, R, 1e-4);
  EXPECT_NEAR(norm(hit), R, 1e-4);
  // Headlight: the centre is brighter than the rim.
  EXPECT_GT(int(img.at(kW / 2, kH / 2)[0]), int(img.at(kW / 2 + int(0.9 * r_px), kH / 2)[0]) + 40);
}

// Several overlapping spheres seen obliquely: coverage and depth agree pixel by pixel with ray casting, so the
// impostors intersect each other correctly (nearest surface wins).
TEST_F(ViewerLayersGl, OverlappingSpheresMatchRayCastingPixelByPixel) {
  const std::vector<Vec3d> c = {{0, 0, 0}, {0.09, 0.04, -0.05}, {-0.12, -0.05, 0.04}, {0.02, -0.02, 0.09}};
  const std::vector<double> r = {0.08, 0.06, 0.04, 0.03};
  OrbitCamera orbit;
  orbit.target = {0, 0, 0};
  orbit.distance_m = 0.55;
  orbit.yaw_rad = 0.4;
  orbit.pitch_rad = 0.3;
  const ViewCamera cam = orbit.view(kW, kH);
  OffscreenTarget target(kW, kH);
  target.bind();
  clearTarget();
  SphereRenderer spheres;
  spheres.upload(c, r);
  spheres.draw(cam, ModelLayerColours::sphere);
  const RgbImage img = readFramebuffer(kW, kH);
  const std::vector<float> depth = readDepth(0, 0, kW, kH);
  std::size_t covered = 0, disagree = 0, compared = 0;
  double worst = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      Vec3d ref;
      const bool want = rayCast(cam, x + 0.5, y + 0.5, c, r, ref);
      covered += want ? 1 : 0;
      if (want != lit(img, x, y)) {
        ++disagree;
        continue;
      }
      if (!want) continue;
      Vec3d got;
      ASSERT_TRUE(pointFromWindowDepth(cam, x + 0.5, y + 0.5, depth[std::size_t(y) * kW + x], got));
      worst = std::max(worst, norm(got - ref));
      ++compared;
    }
  EXPECT_GT(covered, 2000u);
  EXPECT_LE(double(disagree), 0.005 * double(covered));  // grazing rim pixels only (float32 ray maths)
  EXPECT_LT(worst, 5e-4);  // m; 24-bit depth at ~0.5 m resolves ~0.02 mm, grazing rims magnify it
  EXPECT_GT(compared, covered * 9 / 10);
}

// Fixed (yellow), held (magenta) and nodal (green) points show their colours where they project.
TEST_F(ViewerLayersGl, MarkedParticlesShowTheirColoursWhereTheyProject) {
  const ViewCamera cam = frontCamera(0.6);
  RenderLayers l;
  l.fixed_points = {{-0.12, 0.06, 0}, {-0.12, -0.06, 0}};
  l.fixed_ids = {0, 1};
  l.held_points = {{0.12, 0.06, 0}};
  l.held_ids = {2};
  for (int k = 0; k < 8; ++k)  // a 2 cm cube of nodal points (splat radius 0.6 x its spacing: 6 mm)
    l.nodal_points.push_back({k & 1 ? 0.01 : -0.01, (k & 2 ? 0.01 : -0.01) - 0.06, k & 4 ? 0.01 : -0.01});
  OffscreenTarget target(kW, kH);
  target.bind();
  clearTarget();
  ModelLayerRenderer layers;
  layers.upload(l, 0.012);
  ModelLayerToggles on;
  on.constrained = on.nodal_points = true;
  layers.drawOpaque(cam, on, SplatParams{});
  const RgbImage img = readFramebuffer(kW, kH);
  auto at = [&](const Vec3d& p) {
    double px, py, d;
    EXPECT_TRUE(cam.project(p, px, py, d));
    return img.at(int(px), int(py));
  };
  for (const Vec3d& p : l.fixed_points) {
    const auto* c = at(p);
    EXPECT_TRUE(c[0] > 200 && c[1] > 190 && c[2] < 120) << int(c[0]) << "," << int(c[1]) << "," << int(c[2]);
  }
  const auto* h = at(l.held_points[0]);
  EXPECT_TRUE(h[0] > 200 && h[1] < 170 && h[2] > 200) << int(h[0]) << "," << int(h[1]) << "," << int(h[2]);
  for (const Vec3d& p : l.nodal_points) {
    if (p.z < 0) continue;  // behind the front ones
    const auto* c = at(p);
    EXPECT_TRUE(c[1] > 200 && c[0] + 50 < c[1] && c[2] + 50 < c[1])
        << int(c[0]) << "," << int(c[1]) << "," << int(c[2]);
  }
  EXPECT_FALSE(lit(img, kW / 2, kH - 10));  // nothing was drawn up there
  // Switched off, nothing is drawn.
  clearTarget();
  layers.drawOpaque(cam, ModelLayerToggles{}, SplatParams{});
  const RgbImage off = readFramebuffer(kW, kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) ASSERT_FALSE(lit(off, x, y));
}

// The swept surface (a quad in z = 0 through a sphere's centre) blends alpha 0.45 of its colour over what is
// behind it, and is hidden where the sphere's front half is in front of it.
TEST_F(ViewerLayersGl, SweptSurfaceIsTranslucentAndDepthTested) {
  const ViewCamera cam = frontCamera(0.6);
  RenderLayers l;
  l.sphere_centres = {{0, 0, 0}};
  l.sphere_radii = {0.05};
  l.swept_surface.vertices = {{-0.15, -0.1, 0}, {0.15, -0.1, 0}, {0.15, 0.1, 0}, {-0.15, 0.1, 0}};
  l.swept_surface.triangles = {{0, 1, 2}, {0, 2, 3}};
  OffscreenTarget target(kW, kH);
  target.bind();
  clearTarget();
  ModelLayerRenderer layers;
  layers.upload(l, 0.0);
  ModelLayerToggles on;
  on.spheres = true;
  layers.drawOpaque(cam, on, SplatParams{});
  const RgbImage sphere_only = readFramebuffer(kW, kH);
  layers.drawTranslucent(cam, on);
  const RgbImage img = readFramebuffer(kW, kH);
  const auto& sw = ModelLayerColours::swept;
  // Over the black background inside the quad: alpha * colour (8-bit rounding: 2 levels).
  double px, py, d;
  ASSERT_TRUE(cam.project({0.11, 0.07, 0}, px, py, d));
  const auto* bg = img.at(int(px), int(py));
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(bg[k], 255.0 * sw[3] * sw[std::size_t(k)], 2.0) << k;
  // Outside the quad: untouched.
  ASSERT_TRUE(cam.project({0.2, 0.13, 0}, px, py, d));
  EXPECT_FALSE(lit(img, int(px), int(py)));
  // On the sphere, whose front is in front of the quad: exactly the sphere's pixels.
  for (int y = kH / 2 - 5; y <= kH / 2 + 5; ++y)
    for (int x = kW / 2 - 5; x <= kW / 2 + 5; ++x)
      for (int k = 0; k < 3; ++k) ASSERT_EQ(img.at(x, y)[k], sphere_only.at(x, y)[k]);
  // Off: the picture stays the sphere's.
  clearTarget();
  layers.drawOpaque(cam, on, SplatParams{});
  on.swept_surface = false;
  layers.drawTranslucent(cam, on);
  const RgbImage off = readFramebuffer(kW, kH);
  EXPECT_EQ(off.rgb, sphere_only.rgb);
}

// A force arrow: its pixels lie along the projected segment from the origin to origin + scale * F (within the
// head's half-width, 4.5 px, plus a pixel) and cover it from end to end; drawn on top of an occluding sphere.
TEST_F(ViewerLayersGl, ForceArrowPixelsLieAlongTheProjectedSegment) {
  const ViewCamera cam = frontCamera(0.6);
  RenderLayers l;
  const Vec3d origin{-0.08, -0.05, 0.0}, force{0.8, 0.5, 0.2};
  const double scale = 0.25;  // m/N
  l.forces = {{origin, force, ForceArrowKind::Tool}};
  l.sphere_centres = {{0, 0, 0.1}};  // in front of the arrow's middle
  l.sphere_radii = {0.03};
  OffscreenTarget target(kW, kH);
  target.bind();
  clearTarget();
  ModelLayerRenderer layers;
  layers.upload(l, 0.0);
  ModelLayerToggles on;
  on.spheres = true;
  layers.drawOpaque(cam, on, SplatParams{});
  layers.drawForces(cam, on, scale);
  const RgbImage img = readFramebuffer(kW, kH);
  double ax, ay, bx, by, d;
  ASSERT_TRUE(cam.project(origin, ax, ay, d));
  ASSERT_TRUE(cam.project(origin + force * scale, bx, by, d));
  const double len = std::hypot(bx - ax, by - ay);
  ASSERT_GT(len, 60.0);
  std::size_t n = 0;
  double tmin = 1, tmax = 0, worst = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const auto* p = img.at(x, y);
      if (!(p[0] > 200 && p[1] > 80 && p[1] < 180 && p[2] < 60)) continue;  // the tool arrow's orange
      ++n;
      const double qx = x + 0.5 - ax, qy = y + 0.5 - ay;
      const double t = (qx * (bx - ax) + qy * (by - ay)) / (len * len);
      const double tc = std::clamp(t, 0.0, 1.0);
      worst = std::max(worst, std::hypot(qx - tc * (bx - ax), qy - tc * (by - ay)));
      tmin = std::min(tmin, t);
      tmax = std::max(tmax, t);
    }
  EXPECT_GT(double(n), 2.0 * len);  // a 3 px shaft and a head
  EXPECT_LT(worst, 4.5 * 1.05 + 1.0);
  EXPECT_LT(tmin, 0.03);
  EXPECT_GT(tmax, 0.97);
  // No arrow when the layer is off.
  clearTarget();
  layers.drawForces(cam, ModelLayerToggles{false, false, false, false, false}, scale);
  const RgbImage off = readFramebuffer(kW, kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) ASSERT_FALSE(lit(off, x, y));
}

// CPU: the arrow geometry lies in the eye-facing plane of the segment, tip at the apex; the automatic scale
// makes the longest arrow a quarter of the scene radius; the impostor's square covers the tangent cone.
TEST(ViewerLayers, ArrowGeometryAndScale) {
  const ViewCamera cam = frontCamera(0.6);
  std::vector<Vec3d> tri;
  const Vec3d a{0, 0, 0}, b{0.1, 0.05, 0.02};
  arrowTriangles(cam, a, b, 0.002, tri);
  ASSERT_EQ(tri.size(), 9u);
  const Vec3d axis = (b - a) * (1.0 / norm(b - a));
  const Vec3d sight = (a + b) * 0.5 - cam.eye;
  const Vec3d normal = sight - axis * dot(axis, sight);  // of the plane through the segment facing the eye
  for (const Vec3d& v : tri) {
    EXPECT_NEAR(dot(v - a, normal), 0.0, 1e-12);
    const double t = std::clamp(dot(v - a, axis), 0.0, norm(b - a));
    EXPECT_LE(norm(v - (a + axis * t)), 1.5 * 0.002 + 1e-12);
  }
  EXPECT_NEAR(norm(tri.back() - b), 0.0, 1e-15);
  tri.clear();
  arrowTriangles(cam, a, a, 0.002, tri);
  arrowTriangles(cam, {0, 0, 0}, {0, 0, -0.1}, 0.002, tri);  // along the line of sight
  EXPECT_TRUE(tri.empty());

  std::vector<ForceArrow> f = {{{0, 0, 0}, {0, 0, 2}, ForceArrowKind::Tool},
                               {{0, 0, 0}, {0.5, 0, 0}, ForceArrowKind::Particle}};
  EXPECT_DOUBLE_EQ(forceArrowScale(f, 0.0, 0.2), 0.25 * 0.2 / 2.0);
  EXPECT_DOUBLE_EQ(forceArrowScale(f, 0.3, 0.2), 0.3);
  EXPECT_DOUBLE_EQ(forceArrowScale({}, 0.0, 0.2), 0.0);

  // The tangent from the eye at distance d touches the sphere at angle asin(r / d) off the centre ray; it crosses
  // the plane through the centre at d tan(asin(r / d)) from the centre: the square's half-size.
  const double r = 0.1, dist = 0.35;
  EXPECT_NEAR(impostorHalfSize(r, dist, false), dist * std::tan(std::asin(r / dist)), 1e-14);
  EXPECT_DOUBLE_EQ(impostorHalfSize(r, dist, true), r);
  EXPECT_EQ(impostorHalfSize(r, 0.5 * r, false), 0.0);  // the eye inside the sphere
}

}  // namespace
}  // namespace inc::viewer
