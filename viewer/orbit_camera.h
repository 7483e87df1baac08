// The user's orbit/pan/zoom camera around a target point; produces the ViewCamera the renderers use.
#pragma once

#include "physics/vec3.h"
#include "viewer/view_camera.h"

namespace inc::viewer {

struct OrbitCamera {
  Vec3d target{0, 0, 0};   // m, the point orbited about
  bool z_up = false;       // world +z is up (the scenes' convention: gravity along -z); false: +y
  double yaw_rad = 0.6;    // about the up axis
  double pitch_rad = 0.4;  // above the horizontal, clamped to +-(pi/2 - 0.01)
  double distance_m = 1.0;
  double fovy_rad = 0.8;

  Vec3d eye() const;
  Vec3d up() const { return z_up ? Vec3d{0, 0, 1} : Vec3d{0, 1, 0}; }
  // Drag of (dx, dy) pixels: orbit (0.01 rad per pixel), pan (the target moves in the view plane so that
  // the point under the cursor stays under it), zoom (factor > 1 moves away).
  void orbit(double dx_px, double dy_px);
  void pan(double dx_px, double dy_px, int viewport_height_px);
  void zoom(double factor);
  // Frames an axis-aligned box: target at its centre, distance so the bounding sphere fits the view.
  void frameBox(const Vec3d& lo, const Vec3d& hi);
  ViewCamera view(int width_px, int height_px) const;
};

// The 3D point under pixel (px, py) (continuous, pixel centres at +0.5) whose window depth the z-buffer
// holds; false when the depth is the far plane (1.0: nothing drawn there).
bool pointFromWindowDepth(const ViewCamera& cam, double px, double py, double window_depth, Vec3d& out);

}  // namespace inc::viewer
