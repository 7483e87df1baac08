// The GL renderers in a real window (run under xvfb-run with Mesa): splat coverage and depth against a known
// sphere and the CPU reference, picking a 3D point from the z-buffer, and the Phong surface.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "tests/support/viewer_test_support.h"
#include "viewer/gl_window.h"
#include "viewer/offscreen_target.h"
#include "viewer/orbit_camera.h"
#include "viewer/screenshot.h"
#include "viewer/splat_renderer.h"
#include "viewer/surface_renderer.h"
#include "viewer/zbuffer_collision_gl.h"

namespace inc::viewer {
namespace {

using testing::fibonacciSphere;

class ViewerGl : public ::testing::Test {
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
  std::unique_ptr<GlWindow> window_;
};

constexpr int kW = 160, kH = 120;

// Counts pixels that differ from the black background.
double litFraction(const RgbImage& img) {
  std::size_t n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const auto* p = img.at(x, y);
      if (p[0] + p[1] + p[2] > 0) ++n;
    }
  return double(n) / (double(img.width) * img.height);
}

void clearTarget() {
  glClearColor(0, 0, 0, 1);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

TEST_F(ViewerGl, SplatSphereCoverageAndDepthMatchGeometry) {
  const double R = 0.1, dist = 0.6;
  const SplatCloud cloud = fibonacciSphere(3000, R, {0, 0, 0});
  const ViewCamera cam = ViewCamera::lookAlong({0, 0, dist}, {0, 0, -1}, {0, 1, 0}, false, 0.3, 0.05, 5.0, kW, kH);
  OffscreenTarget target(kW, kH);
  target.bind();
  clearTarget();
  SplatRenderer splats;
  splats.upload(cloud);
  SplatParams params;
  splats.draw(cam, params);
  const RgbImage img = readFramebuffer(kW, kH);

  // Analytic: the silhouette of a sphere seen from distance d is a cone of half-angle asin(R / d); on the
  // image plane (tan) its radius is tan(asin(R/d)) / half_height * (H/2) pixels.
  const double r_px = std::tan(std::asin(R / dist)) / 0.3 * (kH / 2.0);
  const double expected = M_PI * r_px * r_px / (double(kW) * kH);
  EXPECT_NEAR(litFraction(img), expected, 0.04 * expected);  // 4 %: tangent-disc rim and pixel quantisation

  // The GL passes agree with the CPU reference pixel by pixel (coverage), allowing the rim's one-pixel ring.
  SplatImage ref;
  rasterizeSplats(cam, cloud, params, ref);
  std::size_t disagree = 0, covered = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const bool gl = img.at(x, y)[0] + img.at(x, y)[1] + img.at(x, y)[2] > 0;
      covered += ref.covered(x, y) ? 1 : 0;
      disagree += (gl != ref.covered(x, y)) ? 1 : 0;
    }
  EXPECT_LT(double(disagree), 0.03 * double(covered));

  // Depth-correct output: the centre pixel's z-buffer depth un-projects to the front pole (0, 0, R) within
  // 1 mm (discs are tangent planes, 24-bit depth at 0.5 m resolves ~0.01 mm).
  const std::vector<float> depth = readDepth(kW / 2, kH / 2, 1, 1);
  Vec3d hit;
  ASSERT_TRUE(pointFromWindowDepth(cam, kW / 2 + 0.5, kH / 2 + 0.5, depth[0], hit));
  EXPECT_NEAR(hit.z, R, 1e-3);
  EXPECT_NEAR(std::hypot(hit.x, hit.y), 0.0, 2e-3);
  OffscreenTarget::bindDefault(64, 64);
}

// Picking: a ray from an off-centre pixel meets the sphere; the z-buffer point must be the analytic hit.
TEST_F(ViewerGl, PickedDepthGivesSurfacePoint) {
  const double R = 0.1;
  const TriangleMesh mesh = testing::icosphere(4, R, {0.02, -0.01, 0.0});
  OrbitCamera orbit;
  orbit.target = {0, 0, 0};
  orbit.distance_m = 0.5;
  orbit.yaw_rad = 0.3;
  orbit.pitch_rad = 0.2;
  const ViewCamera cam = orbit.view(kW, kH);
  OffscreenTarget target(kW, kH);
  target.bind();
  clearTarget();
  SurfaceRenderer surface;
  surface.upload(mesh);
  surface.draw(cam, SurfaceStyle{});
  const std::vector<float> depth = readDepth(0, 0, kW, kH);
  int checked = 0;
  for (int y = 3; y < kH; y += 7)
    for (int x = 3; x < kW; x += 9) {
      Vec3d o, d;
      cam.pixelRay(x + 0.5, y + 0.5, o, d);
      // Analytic ray/sphere hit.
      const Vec3d oc = o - Vec3d{0.02, -0.01, 0.0};
      const double b = dot(oc, d), c = dot(oc, oc) - R * R, disc = b * b - c;
      Vec3d p;
      const bool got = pointFromWindowDepth(cam, x + 0.5, y + 0.5, depth[std::size_t(y) * kW + x], p);
      if (disc < 1e-6 * R * R) {  // clear miss (grazing rays skipped)
        if (disc < -1e-4) {
          EXPECT_FALSE(got) << x << "," << y;
        }
        continue;
      }
      // Inside the silhouette, away from its rim, where the facets deviate by at most R (1 - cos(edge/2)).
      if (disc < 0.2 * R * R) continue;
      ASSERT_TRUE(got) << x << "," << y;
      const Vec3d analytic = o + d * (-b - std::sqrt(disc));
      // Level-4 icosphere: chord sagitta <= R * 0.0011; along a ray at up to ~63 deg incidence that is < 0.5 mm.
      EXPECT_NEAR(norm(p - analytic), 0.0, 5e-4) << x << "," << y;
      ++checked;
    }
  EXPECT_GT(checked, 25);
  OffscreenTarget::bindDefault(64, 64);
}

TEST_F(ViewerGl, SurfaceIsLitFromTheViewerAndCutWallsDiffer) {
  const TriangleMesh mesh = testing::icosphere(3, 0.1, {0, 0, 0});
  const ViewCamera cam = ViewCamera::lookAlong({0, 0, 0.5}, {0, 0, -1}, {0, 1, 0}, false, 0.3, 0.05, 5.0, kW, kH);
  OffscreenTarget target(kW, kH);
  target.bind();
  clearTarget();
  SurfaceRenderer surface;
  surface.upload(mesh);
  const SurfaceStyle style;
  surface.draw(cam, style);
  RgbImage img = readFramebuffer(kW, kH);
  // Headlight: the centre (normal towards the eye) is brighter than a point near the rim.
  const auto* centre = img.at(kW / 2, kH / 2);
  const double r_px = std::tan(std::asin(0.1 / 0.5)) / 0.3 * (kH / 2.0);
  const auto* rim = img.at(kW / 2 + int(0.9 * r_px), kH / 2);
  EXPECT_GT(int(centre[0]), int(rim[0]) + 20);
  // Centre colour: (0.25 + 0.75) * front + specular 0.25, red channel saturates, green near 0.36 + 0.25.
  EXPECT_NEAR(centre[1] / 255.0, std::min(1.0, 0.36 + 0.25), 0.03);
  // The camera inside the sphere sees back faces: the cut-wall colour.
  const ViewCamera inside = ViewCamera::lookAlong({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, false, 0.3, 0.01, 5.0, kW, kH);
  clearTarget();
  surface.draw(inside, style);
  img = readFramebuffer(kW, kH);
  const auto* wall = img.at(kW / 2, kH / 2);
  EXPECT_NEAR(wall[0] / 255.0, std::min(1.0, double(style.back[0]) + style.specular), 0.03);
  EXPECT_NEAR(wall[1] / 255.0, double(style.back[1]) + style.specular, 0.03);
  OffscreenTarget::bindDefault(64, 64);
}

// The GPU split depth passes give the CPU reference's answer and the analytic one (sphere, two lobes).
TEST_F(ViewerGl, ZBufferCollisionMatchesCpuAndGeometry) {
  const double R = 0.1;
  SplatCloud cloud = fibonacciSphere(3000, R, {0, 0, 0});
  const SplatCloud lobe = fibonacciSphere(1500, 0.05, {0, 0, -0.3});  // a second body behind, on the ray
  cloud.centers.insert(cloud.centers.end(), lobe.centers.begin(), lobe.centers.end());
  cloud.normals.insert(cloud.normals.end(), lobe.normals.begin(), lobe.normals.end());
  cloud.radii.insert(cloud.radii.end(), lobe.radii.begin(), lobe.radii.end());
  cloud.colours.insert(cloud.colours.end(), lobe.colours.begin(), lobe.colours.end());
  SplatRenderer splats;
  splats.upload(cloud);
  ZBufferCollider gpu;
  const Vec3d eye{0, 0, 1};
  struct Case {
    double z;  // tip on the z axis
    bool inside;
    double pen;  // analytic penetration along the ray, m
  };
  const Case cases[] = {{0.12, false, 0}, {0.09, true, 0.01},  {0.0, true, 0.1},    {-0.05, true, 0.15},
                        {-0.2, false, 0}, {-0.27, true, 0.02}, {-0.33, true, 0.08}, {-0.4, false, 0}};
  for (const Case& c : cases) {
    const Vec3d tip{0, 0, c.z};
    const ViewCamera cam = cameraRayDepthCamera(eye, tip, 0.01, 5.0, 33);
    const ZContact g = gpu.collide(cam, splats, tip);
    const ZContact r = zbufferCollideCpu(cam, cloud, tip);
    EXPECT_EQ(g.inside, c.inside) << c.z;
    EXPECT_EQ(r.inside, c.inside) << c.z;
    if (c.inside) {
      // float32 view depths on the GPU: 1e-5 m against the CPU; tangent discs: 1 mm against the geometry.
      EXPECT_NEAR(g.penetration_m, r.penetration_m, 1e-5) << c.z;
      EXPECT_NEAR(g.penetration_m, c.pen, 1e-3) << c.z;
      EXPECT_GT(g.normal.z, 0.98) << c.z;  // outward normal of the entry surface faces the eye
    }
  }
  // The caller's framebuffer binding survives.
  GLint bound = -1;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &bound);
  EXPECT_EQ(bound, 0);
}

}  // namespace
}  // namespace inc::viewer
