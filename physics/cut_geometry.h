// Per-element cut geometry: segment/triangle crossing and sphere/triangle overlap against the blade's swept surface.
#pragma once

#include <cmath>

#include "physics/vec3.h"

namespace inc {
namespace cut {

// True when the closed segment [p, q] crosses triangle (a, b, c) (Moller-Trumbore with the segment parameter
// restricted to [0, 1]). The visibility criterion of section 5.2: an MLS neighbour pair or a PBD link whose
// connecting segment crosses the swept surface is removed. A segment lying in the triangle's plane does not cross.
template <typename T>
INC_HD bool segmentCrossesTriangle(const Vec3<T>& p, const Vec3<T>& q, const Vec3<T>& a, const Vec3<T>& b,
                                   const Vec3<T>& c) {
  const Vec3<T> d = q - p;
  const Vec3<T> e1 = b - a;
  const Vec3<T> e2 = c - a;
  const Vec3<T> h = cross(d, e2);
  const T det = dot(e1, h);
  const T scale = norm(e1) * norm(e2) * norm(d);
  if (!(std::fabs(det) > T(1e-12) * scale)) return false;  // parallel or degenerate
  const T inv = T(1) / det;
  const Vec3<T> s = p - a;
  // Barycentric bounds widened by a relative 1e-9: a segment through an edge shared by two swept triangles
  // (the strip's diagonals and pose lines) must hit at least one of them despite rounding (watertight strip).
  const T eps = T(1e-9);
  const T u = dot(s, h) * inv;
  if (u < -eps || u > T(1) + eps) return false;
  const Vec3<T> qv = cross(s, e1);
  const T v = dot(d, qv) * inv;
  if (v < -eps || u + v > T(1) + eps) return false;
  const T t = dot(e2, qv) * inv;
  return t >= T(0) && t <= T(1);
}

// Closest point to p on triangle (a, b, c) by Voronoi-region classification (Ericson, Real-Time Collision
// Detection, 5.1.5; re-derived here).
template <typename T>
INC_HD Vec3<T> closestPointOnTriangle(const Vec3<T>& p, const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c) {
  const Vec3<T> ab = b - a, ac = c - a, ap = p - a;
  const T d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= T(0) && d2 <= T(0)) return a;
  const Vec3<T> bp = p - b;
  const T d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= T(0) && d4 <= d3) return b;
  const T vc = d1 * d4 - d3 * d2;
  if (vc <= T(0) && d1 >= T(0) && d3 <= T(0)) return a + ab * (d1 / (d1 - d3));
  const Vec3<T> cp = p - c;
  const T d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= T(0) && d5 <= d6) return c;
  const T vb = d5 * d2 - d1 * d6;
  if (vb <= T(0) && d2 >= T(0) && d6 <= T(0)) return a + ac * (d2 / (d2 - d6));
  const T va = d3 * d6 - d5 * d4;
  if (va <= T(0) && (d4 - d3) >= T(0) && (d5 - d6) >= T(0)) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const T denom = T(1) / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// A sphere is cut when the swept triangle passes within its radius: |closest(c) - c| < r (open ball, so a
// blade grazing the sphere's surface does not convert it).
template <typename T>
INC_HD bool sphereTouchesTriangle(const Vec3<T>& centre, T radius, const Vec3<T>& a, const Vec3<T>& b,
                                  const Vec3<T>& c) {
  const Vec3<T> k = closestPointOnTriangle(centre, a, b, c);
  return norm2(k - centre) < radius * radius;
}

}  // namespace cut
}  // namespace inc
