// Orbit camera arithmetic and un-projection of a z-buffer depth to the 3D point under the cursor.
#include "viewer/orbit_camera.h"

#include <algorithm>
#include <cmath>

namespace inc::viewer {

Vec3d OrbitCamera::eye() const {
  const double cp = std::cos(pitch_rad), sp = std::sin(pitch_rad);
  // z up: yaw 0 looks along +y from its -y side (x to the right); y up: along -z from +z, as before.
  const Vec3d dir = z_up ? Vec3d{cp * std::sin(yaw_rad), -cp * std::cos(yaw_rad), sp}
                         : Vec3d{cp * std::sin(yaw_rad), sp, cp * std::cos(yaw_rad)};
  return target + dir * distance_m;
}

void OrbitCamera::orbit(double dx_px, double dy_px) {
  yaw_rad -= 0.01 * dx_px;
  const double lim = M_PI / 2 - 0.01;
  pitch_rad = std::clamp(pitch_rad + 0.01 * dy_px, -lim, lim);
}

void OrbitCamera::pan(double dx_px, double dy_px, int viewport_height_px) {
  const ViewCamera v = view(std::max(1, viewport_height_px), std::max(1, viewport_height_px));
  // Metres per pixel at the target's depth.
  const double m_per_px = 2.0 * std::tan(0.5 * fovy_rad) * distance_m / std::max(1, viewport_height_px);
  target = target - v.right * (dx_px * m_per_px) + v.up * (dy_px * m_per_px);
}

void OrbitCamera::zoom(double factor) { distance_m = std::clamp(distance_m * factor, 1e-4, 1e4); }

void OrbitCamera::frameBox(const Vec3d& lo, const Vec3d& hi) {
  target = (lo + hi) * 0.5;
  const double r = std::max(0.5 * norm(hi - lo), 1e-3);
  distance_m = 1.2 * r / std::sin(0.5 * fovy_rad);
}

ViewCamera OrbitCamera::view(int width_px, int height_px) const {
  const Vec3d e = eye();
  // Near/far bracket the bounding sphere implied by the distance so depth precision stays useful.
  const double near_m = std::max(1e-4, 0.01 * distance_m);
  return ViewCamera::lookAlong(e, target - e, up(), false, std::tan(0.5 * fovy_rad), near_m, 100.0 * distance_m,
                               std::max(1, width_px), std::max(1, height_px));
}

bool pointFromWindowDepth(const ViewCamera& cam, double px, double py, double window_depth, Vec3d& out) {
  if (!(window_depth < 1.0) || !(window_depth >= 0.0)) return false;
  const double z = cam.viewDepthFromWindow(window_depth);
  Vec3d o, d;
  cam.pixelRay(px, py, o, d);
  out = o + d * (z / dot(d, cam.forward));
  return true;
}

}  // namespace inc::viewer
