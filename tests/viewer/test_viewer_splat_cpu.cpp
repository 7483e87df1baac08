// CPU reference for point splatting and the z-buffer tool collision, against a sphere of known geometry.
#include <gtest/gtest.h>

#include <cmath>

#include "tests/support/viewer_test_support.h"
#include "viewer/splat_raster.h"
#include "viewer/view_camera.h"
#include "viewer/zbuffer_collision.h"

namespace inc::viewer {
namespace {

using testing::coveredFraction;
using testing::fibonacciSphere;

TEST(ViewerCamera, ProjectAndPixelRayAreInverse) {
  const ViewCamera cam =
      ViewCamera::lookAlong({0.3, 0.2, 1.0}, {-0.3, -0.2, -1.0}, {0, 1, 0}, false, 0.5, 0.01, 10.0, 80, 60);
  const Vec3d p{0.05, -0.02, 0.1};
  double px, py, z;
  ASSERT_TRUE(cam.project(p, px, py, z));
  Vec3d o, d;
  cam.pixelRay(px, py, o, d);
  const Vec3d back = o + d * (z / dot(d, cam.forward));
  EXPECT_NEAR(norm(back - p), 0.0, 1e-12);
  // The depth mapping and its inverse (what picking from the z-buffer uses).
  for (double zz : {0.02, 0.5, 3.0, 9.0}) EXPECT_NEAR(cam.viewDepthFromWindow(cam.windowDepth(zz)), zz, 1e-9 * zz);
}

TEST(ViewerCamera, MatricesAgreeWithProject) {
  const ViewCamera cam =
      ViewCamera::lookAlong({0.1, 0.4, 0.8}, {-0.1, -0.4, -0.8}, {0, 1, 0}, false, 0.4, 0.05, 5.0, 64, 48);
  const Mat4f pv = cam.projectionMatrix() * cam.viewMatrix();
  const Vec3d p{0.02, 0.01, -0.03};
  float clip[4] = {0, 0, 0, 0};
  for (int r = 0; r < 4; ++r)
    clip[r] = pv.at(r, 0) * float(p.x) + pv.at(r, 1) * float(p.y) + pv.at(r, 2) * float(p.z) + pv.at(r, 3);
  double px, py, z;
  ASSERT_TRUE(cam.project(p, px, py, z));
  // float matrices: 1e-5 relative is what single precision allows here.
  EXPECT_NEAR((clip[0] / clip[3] * 0.5 + 0.5) * cam.width, px, 1e-3);
  EXPECT_NEAR((clip[1] / clip[3] * 0.5 + 0.5) * cam.height, py, 1e-3);
  EXPECT_NEAR(clip[2] / clip[3] * 0.5 + 0.5, cam.windowDepth(z), 1e-5);
}

// A sphere of radius R seen orthographically covers pi R^2 of the view window.
TEST(ViewerSplatCpu, SphereCoversAnalyticScreenFraction) {
  const double R = 0.1;
  const SplatCloud cloud = fibonacciSphere(3000, R, {0, 0, 0}, 1.0);
  const ViewCamera cam = ViewCamera::lookAlong({0, 0, 1}, {0, 0, -1}, {0, 1, 0}, true, 0.2, 0.01, 3.0, 128, 128);
  SplatImage img;
  rasterizeSplats(cam, cloud, SplatParams{}, img);
  const double expected = M_PI * R * R / (0.4 * 0.4);
  // Tolerance 3 %: the silhouette is made of tangent discs (they reach R + r^2 / 2R) and pixel quantisation.
  EXPECT_NEAR(coveredFraction(img), expected, 0.03 * expected);
  // Centre pixel: the nearest depth is the front pole at view depth 1 - R (discs tangent there; 1 mm).
  const std::size_t c = std::size_t(64) * 128 + 64;
  EXPECT_NEAR(img.nearest_depth[c], 1.0 - R, 1e-3);
  // The blended normal there faces the viewer.
  EXPECT_GT(img.normal[3 * c + 2], 0.99f);
  // No hole inside the silhouette (radius 0.9 R).
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) {
      const double sx = ((x + 0.5) / 128 * 2 - 1) * 0.2, sy = ((y + 0.5) / 128 * 2 - 1) * 0.2;
      if (sx * sx + sy * sy < 0.81 * R * R) {
        ASSERT_TRUE(img.covered(x, y)) << x << "," << y;
      }
    }
}

TEST(ViewerZCollision, TipInsideAndOutsideSphere) {
  const double R = 0.1;
  const SplatCloud cloud = fibonacciSphere(3000, R, {0, 0, 0}, 1.0);
  const Vec3d eye{0.05, 0.3, 1.0};
  for (double depth_in : {0.01, 0.03, 0.08}) {
    // Tip on the line from the eye through the sphere centre, depth_in below the first surface.
    const Vec3d dir = (Vec3d{0, 0, 0} - eye) * (1.0 / norm(eye));
    const Vec3d tip = eye + dir * (norm(eye) - R + depth_in);
    const ViewCamera cam = cameraRayDepthCamera(eye, tip, 0.01, 5.0, 33);
    const ZContact c = zbufferCollideCpu(cam, cloud, tip);
    EXPECT_TRUE(c.inside) << depth_in;
    // Entry point within 1 mm of the analytic one; penetration likewise (the discs are tangent planes).
    EXPECT_NEAR(c.penetration_m, depth_in, 1e-3);
    EXPECT_NEAR(norm(c.surface_point), R, 1e-3);
    EXPECT_GT(dot(c.normal, -dir), 0.98);
  }
  // Outside: in front of the sphere, behind it, and beside it.
  const Vec3d dir = (Vec3d{0, 0, 0} - eye) * (1.0 / norm(eye));
  for (const Vec3d& tip : {eye + dir * (norm(eye) - R - 0.01), eye + dir * (norm(eye) + R + 0.01), Vec3d{0.15, 0, 0}}) {
    const ViewCamera cam = cameraRayDepthCamera(eye, tip, 0.01, 5.0, 33);
    EXPECT_FALSE(zbufferCollideCpu(cam, cloud, tip).inside);
  }
  // Tool-axis view gives the same answer independent of the user's eye.
  const Vec3d tip{0.0, 0.0, R - 0.02};
  const ViewCamera ax = toolAxisDepthCamera(tip, {0, 0, -1}, 0.5, 0.01, 33);
  const ZContact c = zbufferCollideCpu(ax, cloud, tip);
  EXPECT_TRUE(c.inside);
  EXPECT_NEAR(c.penetration_m, 0.02, 1e-3);
}

// Two lobes on one ray: the tip inside the second must still count (the split passes handle it).
TEST(ViewerZCollision, TipInsideSecondLobe) {
  SplatCloud a = fibonacciSphere(1500, 0.05, {0, 0, 0.1});
  const SplatCloud b = fibonacciSphere(1500, 0.05, {0, 0, -0.1});
  a.centers.insert(a.centers.end(), b.centers.begin(), b.centers.end());
  a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
  a.radii.insert(a.radii.end(), b.radii.begin(), b.radii.end());
  a.colours.insert(a.colours.end(), b.colours.begin(), b.colours.end());
  const Vec3d eye{0, 0, 1};
  EXPECT_TRUE(zbufferCollideCpu(cameraRayDepthCamera(eye, {0, 0, -0.1}, 0.01, 5, 33), a, {0, 0, -0.1}).inside);
  EXPECT_FALSE(zbufferCollideCpu(cameraRayDepthCamera(eye, {0, 0, 0}, 0.01, 5, 33), a, {0, 0, 0}).inside);
}

}  // namespace
}  // namespace inc::viewer
