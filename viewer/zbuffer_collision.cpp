// Z-buffer tool-tip collision on the CPU: depth passes split at the tip, read under the tip.
#include "viewer/zbuffer_collision.h"

#include <cmath>
#include <limits>

namespace inc::viewer {

ViewCamera toolAxisDepthCamera(const Vec3d& tip, const Vec3d& axis, double reach_m, double half_width_m, int res) {
  res |= 1;  // odd: the centre pixel's centre is the image centre, so its ray is the tool axis
  const Vec3d a = normalizeOr(axis, Vec3d{0, 0, -1});
  return ViewCamera::lookAlong(tip - a * reach_m, a, anyPerpendicular(a), /*ortho=*/true, half_width_m,
                               /*near=*/0.0, /*far=*/2.0 * reach_m, res, res);
}

ViewCamera cameraRayDepthCamera(const Vec3d& eye, const Vec3d& tip, double half_width_m, double far_m, int res) {
  res |= 1;
  const double dist = std::max(norm(tip - eye), 1e-6);
  const Vec3d dir = normalizeOr(tip - eye, Vec3d{0, 0, -1});
  // half_height = tan(fovy/2) chosen so the window spans +-half_width_m at the tip's distance.
  return ViewCamera::lookAlong(eye, dir, anyPerpendicular(dir), /*ortho=*/false, half_width_m / dist,
                               std::min(1e-3, 0.1 * dist), far_m, res, res);
}

void rasterizeTipDepth(const ViewCamera& cam, const SplatCloud& cloud, const Vec3d& tip, TipDepthBuffers& out) {
  const float inf = std::numeric_limits<float>::infinity();
  const std::size_t npix = std::size_t(cam.width) * cam.height;
  out.width = cam.width;
  out.height = cam.height;
  out.tip_depth = cam.viewDepth(tip);
  out.before_depth.assign(npix, -inf);
  out.after_depth.assign(npix, inf);
  out.before_facing.assign(npix, 0.0f);
  out.after_facing.assign(npix, 0.0f);
  out.before_normal.assign(npix * 3, 0.0f);
  out.after_normal.assign(npix * 3, 0.0f);
  const double zt = out.tip_depth;

  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vec3d n = splatNormalForView(cam, cloud.centers[i], i < cloud.normals.size() ? cloud.normals[i] : Vec3d{});
    const double r = cloud.radii[i];
    int x0, y0, x1, y1;
    if (!splatPixelBounds(cam, cloud.centers[i], n, r, x0, y0, x1, y1)) continue;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        Vec3d o, d;
        cam.pixelRay(x + 0.5, y + 0.5, o, d);
        double t, rho2;
        if (!intersectSplatPlane(o, d, cloud.centers[i], n, t, rho2) || rho2 > r * r) continue;
        const double z = t * dot(d, cam.forward);
        const float facing = dot(n, d) < 0.0 ? 1.0f : -1.0f;
        const std::size_t p = out.index(x, y);
        if (z < zt) {
          if (z > out.before_depth[p]) {  // depth test GREATER among surfaces in front of the tip
            out.before_depth[p] = float(z);
            out.before_facing[p] = facing;
            for (int k = 0; k < 3; ++k) out.before_normal[3 * p + k] = float(n[k]);
          }
        } else if (z < out.after_depth[p]) {  // depth test LESS among surfaces behind the tip
          out.after_depth[p] = float(z);
          out.after_facing[p] = facing;
          for (int k = 0; k < 3; ++k) out.after_normal[3 * p + k] = float(n[k]);
        }
      }
  }
}

ZContact readTipContact(const ViewCamera& cam, const TipDepthBuffers& buf, const Vec3d& tip) {
  ZContact c;
  double px, py, depth;
  if (!cam.project(tip, px, py, depth)) return c;
  const int x = int(std::floor(px)), y = int(std::floor(py));
  if (x < 0 || y < 0 || x >= buf.width || y >= buf.height) return c;
  const std::size_t p = buf.index(x, y);
  c.surface_before = std::isfinite(buf.before_depth[p]);
  c.surface_after = std::isfinite(buf.after_depth[p]);
  c.before_depth = buf.before_depth[p];
  c.after_depth = buf.after_depth[p];
  // Paper's (a): tip beyond a front-facing surface; (b): before a back-facing one.
  c.inside = c.surface_before && buf.before_facing[p] > 0.0f && c.surface_after && buf.after_facing[p] < 0.0f;
  if (c.surface_before) {
    Vec3d o, d;
    cam.pixelRay(x + 0.5, y + 0.5, o, d);
    const double t = c.before_depth / dot(d, cam.forward);
    c.surface_point = o + d * t;
    c.normal =
        normalizeOr(Vec3d{buf.before_normal[3 * p], buf.before_normal[3 * p + 1], buf.before_normal[3 * p + 2]}, -d);
    // Along the ray: the tip sits on the centre ray, so this is its distance past the entry point.
    c.penetration_m = norm(tip - o) - t;
  }
  return c;
}

ZContact zbufferCollideCpu(const ViewCamera& cam, const SplatCloud& cloud, const Vec3d& tip) {
  TipDepthBuffers buf;
  rasterizeTipDepth(cam, cloud, tip, buf);
  return readTipContact(cam, buf, tip);
}

}  // namespace inc::viewer
