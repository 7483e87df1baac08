// View and projection matrices, pixel rays and projection for ViewCamera (GL conventions, metres).
#include "viewer/view_camera.h"

#include <cmath>

namespace inc::viewer {

Mat4f Mat4f::identity() {
  Mat4f a;
  for (int i = 0; i < 4; ++i) a.at(i, i) = 1.0f;
  return a;
}

Mat4f operator*(const Mat4f& a, const Mat4f& b) {
  Mat4f c;
  for (int r = 0; r < 4; ++r)
    for (int col = 0; col < 4; ++col) {
      float s = 0.0f;
      for (int k = 0; k < 4; ++k) s += a.at(r, k) * b.at(k, col);
      c.at(r, col) = s;
    }
  return c;
}

Mat4f inverse(const Mat4f& a) {
  // Gauss-Jordan in double with partial pivoting: the matrices here are small and well conditioned.
  double m[4][8];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      m[r][c] = a.at(r, c);
      m[r][c + 4] = (r == c) ? 1.0 : 0.0;
    }
  for (int c = 0; c < 4; ++c) {
    int piv = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::fabs(m[r][c]) > std::fabs(m[piv][c])) piv = r;
    if (std::fabs(m[piv][c]) < 1e-300) return Mat4f::identity();
    if (piv != c)
      for (int k = 0; k < 8; ++k) std::swap(m[c][k], m[piv][k]);
    const double inv = 1.0 / m[c][c];
    for (int k = 0; k < 8; ++k) m[c][k] *= inv;
    for (int r = 0; r < 4; ++r) {
      if (r == c) continue;
      const double f = m[r][c];
      for (int k = 0; k < 8; ++k) m[r][k] -= f * m[c][k];
    }
  }
  Mat4f out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out.at(r, c) = float(m[r][c + 4]);
  return out;
}

Mat4f frameMatrix(const Vec3d& x, const Vec3d& y, const Vec3d& z, const Vec3d& t) {
  Mat4f a = Mat4f::identity();
  for (int r = 0; r < 3; ++r) {
    a.at(r, 0) = float(x[r]);
    a.at(r, 1) = float(y[r]);
    a.at(r, 2) = float(z[r]);
    a.at(r, 3) = float(t[r]);
  }
  return a;
}

Vec3d normalizeOr(const Vec3d& v, const Vec3d& fallback) {
  const double n = norm(v);
  if (!(n > 1e-300) || !std::isfinite(n)) return fallback;
  return v * (1.0 / n);
}

Vec3d anyPerpendicular(const Vec3d& n) {
  // Cross with the world axis least aligned with n, so the result never degenerates.
  const Vec3d a = (std::fabs(n.x) < 0.57) ? Vec3d{1, 0, 0} : (std::fabs(n.y) < 0.57 ? Vec3d{0, 1, 0} : Vec3d{0, 0, 1});
  return normalizeOr(cross(n, a), Vec3d{0, 0, 1});
}

ViewCamera ViewCamera::lookAlong(const Vec3d& eye, const Vec3d& dir, const Vec3d& up_hint, bool ortho,
                                 double half_height, double near_m, double far_m, int width, int height) {
  ViewCamera c;
  c.eye = eye;
  c.forward = normalizeOr(dir, Vec3d{0, 0, -1});
  Vec3d r = cross(c.forward, up_hint);
  if (norm(r) < 1e-9) r = anyPerpendicular(c.forward);
  c.right = normalizeOr(r, Vec3d{1, 0, 0});
  c.up = cross(c.right, c.forward);
  c.orthographic = ortho;
  c.half_height = half_height;
  c.near_m = near_m;
  c.far_m = far_m;
  c.width = width;
  c.height = height;
  return c;
}

void ViewCamera::pixelRay(double px, double py, Vec3d& origin, Vec3d& dir) const {
  const double sx = (2.0 * px / width - 1.0) * half_height * aspect();
  const double sy = (2.0 * py / height - 1.0) * half_height;
  if (orthographic) {
    origin = eye + right * sx + up * sy;
    dir = forward;
  } else {
    origin = eye;
    dir = normalizeOr(forward + right * sx + up * sy, forward);
  }
}

bool ViewCamera::project(const Vec3d& p, double& px, double& py, double& depth) const {
  const Vec3d d = p - eye;
  depth = dot(d, forward);
  double sx = dot(d, right), sy = dot(d, up);
  if (!orthographic) {
    if (depth <= 1e-12) return false;
    sx /= depth;
    sy /= depth;
  }
  px = (sx / (half_height * aspect()) + 1.0) * 0.5 * width;
  py = (sy / half_height + 1.0) * 0.5 * height;
  return true;
}

Mat4f ViewCamera::viewMatrix() const {
  const Vec3d back = -forward;
  Mat4f v = Mat4f::identity();
  for (int c = 0; c < 3; ++c) {
    v.at(0, c) = float(right[c]);
    v.at(1, c) = float(up[c]);
    v.at(2, c) = float(back[c]);
  }
  v.at(0, 3) = float(-dot(right, eye));
  v.at(1, 3) = float(-dot(up, eye));
  v.at(2, 3) = float(-dot(back, eye));
  return v;
}

Mat4f ViewCamera::projectionMatrix() const {
  Mat4f p;
  const double n = near_m, f = far_m;
  if (orthographic) {
    p.at(0, 0) = float(1.0 / (half_height * aspect()));
    p.at(1, 1) = float(1.0 / half_height);
    p.at(2, 2) = float(-2.0 / (f - n));
    p.at(2, 3) = float(-(f + n) / (f - n));
    p.at(3, 3) = 1.0f;
  } else {
    const double fy = 1.0 / half_height;
    p.at(0, 0) = float(fy / aspect());
    p.at(1, 1) = float(fy);
    p.at(2, 2) = float((f + n) / (n - f));
    p.at(2, 3) = float(2.0 * f * n / (n - f));
    p.at(3, 2) = -1.0f;
  }
  return p;
}

double ViewCamera::windowDepth(double z) const {
  const double n = near_m, f = far_m;
  if (orthographic) return (z - n) / (f - n);
  // ndc = (f + n)/(f - n) - 2 f n / ((f - n) z), the GL perspective depth.
  const double ndc = (f + n) / (f - n) - 2.0 * f * n / ((f - n) * z);
  return 0.5 * ndc + 0.5;
}

double ViewCamera::viewDepthFromWindow(double d) const {
  const double n = near_m, f = far_m;
  if (orthographic) return n + d * (f - n);
  const double ndc = 2.0 * d - 1.0;
  return 2.0 * f * n / ((f + n) - ndc * (f - n));
}

}  // namespace inc::viewer
