// Small fixed-size 3-vector and 3x3 matrix types for the shared host/device physics math.
#pragma once

#include <cmath>

#include "physics/hd.h"

namespace inc {

template <typename T>
struct Vec3 {
  T x, y, z;
  INC_HD Vec3() : x(T(0)), y(T(0)), z(T(0)) {}
  INC_HD Vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
  template <typename U>
  INC_HD explicit Vec3(const Vec3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}
  INC_HD T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  INC_HD const T& operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  INC_HD Vec3& operator+=(const Vec3& o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  INC_HD Vec3& operator-=(const Vec3& o) {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  INC_HD Vec3& operator*=(T s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
};

template <typename T>
INC_HD Vec3<T> operator+(Vec3<T> a, const Vec3<T>& b) {
  return a += b;
}
template <typename T>
INC_HD Vec3<T> operator-(Vec3<T> a, const Vec3<T>& b) {
  return a -= b;
}
template <typename T>
INC_HD Vec3<T> operator-(const Vec3<T>& a) {
  return {-a.x, -a.y, -a.z};
}
template <typename T>
INC_HD Vec3<T> operator*(Vec3<T> a, T s) {
  return a *= s;
}
template <typename T>
INC_HD Vec3<T> operator*(T s, Vec3<T> a) {
  return a *= s;
}
template <typename T>
INC_HD Vec3<T> operator/(const Vec3<T>& a, T s) {
  return {a.x / s, a.y / s, a.z / s};
}
template <typename T>
INC_HD T dot(const Vec3<T>& a, const Vec3<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename T>
INC_HD Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
INC_HD T norm2(const Vec3<T>& a) {
  return dot(a, a);
}
template <typename T>
INC_HD T norm(const Vec3<T>& a) {
  return std::sqrt(dot(a, a));
}
template <typename T>
INC_HD bool isFinite(const Vec3<T>& a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

// Row-major 3x3 matrix: m[r][c].
template <typename T>
struct Mat3 {
  T m[3][3];
  INC_HD Mat3() {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m[r][c] = T(0);
  }
  INC_HD static Mat3 identity() {
    Mat3 a;
    a.m[0][0] = a.m[1][1] = a.m[2][2] = T(1);
    return a;
  }
  INC_HD static Mat3 diag(T d) {
    Mat3 a;
    a.m[0][0] = a.m[1][1] = a.m[2][2] = d;
    return a;
  }
  INC_HD static Mat3 fromRows(const Vec3<T>& r0, const Vec3<T>& r1, const Vec3<T>& r2) {
    Mat3 a;
    for (int c = 0; c < 3; ++c) {
      a.m[0][c] = r0[c];
      a.m[1][c] = r1[c];
      a.m[2][c] = r2[c];
    }
    return a;
  }
  template <typename U>
  INC_HD explicit Mat3(const Mat3<U>& o) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m[r][c] = T(o.m[r][c]);
  }
  INC_HD T& operator()(int r, int c) { return m[r][c]; }
  INC_HD const T& operator()(int r, int c) const { return m[r][c]; }
  INC_HD Vec3<T> row(int r) const { return {m[r][0], m[r][1], m[r][2]}; }
  INC_HD Vec3<T> col(int c) const { return {m[0][c], m[1][c], m[2][c]}; }
  INC_HD Mat3& operator+=(const Mat3& o) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m[r][c] += o.m[r][c];
    return *this;
  }
  INC_HD Mat3& operator-=(const Mat3& o) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m[r][c] -= o.m[r][c];
    return *this;
  }
  INC_HD Mat3& operator*=(T s) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m[r][c] *= s;
    return *this;
  }
};

template <typename T>
INC_HD Mat3<T> operator+(Mat3<T> a, const Mat3<T>& b) {
  return a += b;
}
template <typename T>
INC_HD Mat3<T> operator-(Mat3<T> a, const Mat3<T>& b) {
  return a -= b;
}
template <typename T>
INC_HD Mat3<T> operator*(Mat3<T> a, T s) {
  return a *= s;
}
template <typename T>
INC_HD Mat3<T> operator*(T s, Mat3<T> a) {
  return a *= s;
}

template <typename T>
INC_HD Mat3<T> operator*(const Mat3<T>& a, const Mat3<T>& b) {
  Mat3<T> c;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) c.m[r][j] += a.m[r][k] * b.m[k][j];
  return c;
}
template <typename T>
INC_HD Vec3<T> operator*(const Mat3<T>& a, const Vec3<T>& v) {
  return {a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z, a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
          a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z};
}
template <typename T>
INC_HD Mat3<T> transpose(const Mat3<T>& a) {
  Mat3<T> t;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) t.m[r][c] = a.m[c][r];
  return t;
}
// a b^T
template <typename T>
INC_HD Mat3<T> outer(const Vec3<T>& a, const Vec3<T>& b) {
  Mat3<T> o;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) o.m[r][c] = a[r] * b[c];
  return o;
}
template <typename T>
INC_HD T trace(const Mat3<T>& a) {
  return a.m[0][0] + a.m[1][1] + a.m[2][2];
}
// Frobenius inner product A : B.
template <typename T>
INC_HD T ddot(const Mat3<T>& a, const Mat3<T>& b) {
  T s = T(0);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) s += a.m[r][c] * b.m[r][c];
  return s;
}
template <typename T>
INC_HD T det(const Mat3<T>& a) {
  return a.m[0][0] * (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) -
         a.m[0][1] * (a.m[1][0] * a.m[2][2] - a.m[1][2] * a.m[2][0]) +
         a.m[0][2] * (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]);
}
// Transposed cofactor matrix: adj(A) with A adj(A) = det(A) I.
template <typename T>
INC_HD Mat3<T> adjugate(const Mat3<T>& a) {
  Mat3<T> c;
  c.m[0][0] = a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1];
  c.m[0][1] = a.m[0][2] * a.m[2][1] - a.m[0][1] * a.m[2][2];
  c.m[0][2] = a.m[0][1] * a.m[1][2] - a.m[0][2] * a.m[1][1];
  c.m[1][0] = a.m[1][2] * a.m[2][0] - a.m[1][0] * a.m[2][2];
  c.m[1][1] = a.m[0][0] * a.m[2][2] - a.m[0][2] * a.m[2][0];
  c.m[1][2] = a.m[0][2] * a.m[1][0] - a.m[0][0] * a.m[1][2];
  c.m[2][0] = a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0];
  c.m[2][1] = a.m[0][1] * a.m[2][0] - a.m[0][0] * a.m[2][1];
  c.m[2][2] = a.m[0][0] * a.m[1][1] - a.m[0][1] * a.m[1][0];
  return c;
}
template <typename T>
INC_HD T frobeniusNorm(const Mat3<T>& a) {
  return std::sqrt(ddot(a, a));
}
template <typename T>
INC_HD bool isFinite(const Mat3<T>& a) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(a.m[r][c])) return false;
  return true;
}

using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;
using Mat3f = Mat3<float>;
using Mat3d = Mat3<double>;

}  // namespace inc
