// A pinhole or orthographic view (eye, axes, frustum, pixel grid) shared by the GL renderer and the CPU rasteriser.
#pragma once

#include <array>

#include "physics/vec3.h"

namespace inc::viewer {

// Column-major 4x4 matrix, as OpenGL takes it: m[col * 4 + row].
struct Mat4f {
  std::array<float, 16> m{};
  static Mat4f identity();
  float& at(int row, int col) { return m[col * 4 + row]; }
  float at(int row, int col) const { return m[col * 4 + row]; }
  const float* data() const { return m.data(); }
};
Mat4f operator*(const Mat4f& a, const Mat4f& b);
// General inverse (cofactors); returns identity for a singular matrix.
Mat4f inverse(const Mat4f& a);
// Rigid placement: columns x, y, z axes (world), translation t.
Mat4f frameMatrix(const Vec3d& x, const Vec3d& y, const Vec3d& z, const Vec3d& t);

Vec3d normalizeOr(const Vec3d& v, const Vec3d& fallback);
// Any unit vector orthogonal to the unit vector n (stable choice of the helper axis).
Vec3d anyPerpendicular(const Vec3d& n);

// The view: right/up/forward are an orthonormal right-handed frame (right x up = -forward, GL convention:
// the camera looks down its -z axis). Depth values are "view depth": distance along `forward`, metres.
// Pixel (0, 0) is the bottom-left pixel, as glReadPixels returns it; pixel centres sit at +0.5.
struct ViewCamera {
  Vec3d eye{0, 0, 1};
  Vec3d forward{0, 0, -1};
  Vec3d up{0, 1, 0};
  Vec3d right{1, 0, 0};
  bool orthographic = false;
  double half_height = 0.41421356;  // perspective: tan(fovy / 2); orthographic: half the view height, m
  double near_m = 0.01;
  double far_m = 10.0;
  int width = 64;
  int height = 64;

  // A camera at `eye` looking along `dir`, with `up_hint` defining the roll (any non-parallel vector).
  static ViewCamera lookAlong(const Vec3d& eye, const Vec3d& dir, const Vec3d& up_hint, bool orthographic,
                              double half_height, double near_m, double far_m, int width, int height);

  double aspect() const { return double(width) / double(height); }
  // Ray through a continuous pixel position (px, py); pixel centres at integer + 0.5. dir is unit length.
  void pixelRay(double px, double py, Vec3d& origin, Vec3d& dir) const;
  // Projects a world point to continuous pixel coordinates and view depth; false when not in front of the eye.
  bool project(const Vec3d& p, double& px, double& py, double& depth) const;
  double viewDepth(const Vec3d& p) const { return dot(p - eye, forward); }

  Mat4f viewMatrix() const;
  Mat4f projectionMatrix() const;
  // Window depth in [0, 1] that the projection matrix gives a point at view depth z (for gl_FragDepth / readback).
  double windowDepth(double z) const;
  // Inverse of windowDepth: view depth from a depth-buffer value.
  double viewDepthFromWindow(double d) const;
};

}  // namespace inc::viewer
