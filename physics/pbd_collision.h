// Sphere-vs-collider contacts as unilateral position constraints: static planes and boxes, moving tool capsules.
#pragma once

#include <cmath>

#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc::pbd {

// Half-space n . x >= offset is free; the body side is below it (n unit).
template <typename T>
struct PlaneCollider {
  Vec3<T> normal{T(0), T(0), T(1)};
  T offset = T(0);    // m
  T friction = T(0);  // Coulomb coefficient mu (0: frictionless)
};

// Solid axis-aligned box the organ must stay out of.
template <typename T>
struct BoxCollider {
  Vec3<T> min, max;   // m
  T friction = T(0);  // Coulomb coefficient mu (0: frictionless)
};

// A tool: the segment a-b swept by a ball of `radius` (m).
template <typename T>
struct CapsuleCollider {
  Vec3<T> a, b;
  T radius = T(0);
  T friction = T(0);  // Coulomb coefficient mu against the tissue (0: frictionless)
};

// Each contact is C(x) = signed distance between the sphere (centre x, radius r) and the collider >= 0,
// a unilateral constraint with zero compliance: when violated, the centre is moved along the contact
// normal by -C (the single-particle XPBD step with alpha = 0 does not depend on its inverse mass).
// Returns the correction (zero when not in contact).
template <typename T>
INC_HD Vec3<T> planeContact(const Vec3<T>& x, T r, const PlaneCollider<T>& p) {
  const T c = dot(p.normal, x) - p.offset - r;
  return c < T(0) ? p.normal * (-c) : Vec3<T>();
}

template <typename T>
INC_HD Vec3<T> boxContact(const Vec3<T>& x, T r, const BoxCollider<T>& b) {
  Vec3<T> q;
  bool inside = true;
  for (int k = 0; k < 3; ++k) {
    T v = x[k];
    if (v < b.min[k]) {
      v = b.min[k];
      inside = false;
    }
    if (v > b.max[k]) {
      v = b.max[k];
      inside = false;
    }
    q[k] = v;
  }
  if (!inside) {
    const Vec3<T> d = x - q;
    const T dist = norm(d);
    if (dist >= r || !(dist > T(0))) return Vec3<T>();
    return d * ((r - dist) / dist);
  }
  // Centre inside the box: leave through the nearest face (ties: lowest axis, min side first).
  int axis = 0;
  T best = x[0] - b.min[0], sign = T(-1);
  for (int k = 0; k < 3; ++k) {
    const T to_min = x[k] - b.min[k], to_max = b.max[k] - x[k];
    if (to_min < best) {
      best = to_min;
      axis = k;
      sign = T(-1);
    }
    if (to_max < best) {
      best = to_max;
      axis = k;
      sign = T(1);
    }
  }
  Vec3<T> out;
  out[axis] = sign * (best + r);
  return out;
}

// Position-based Coulomb friction after a static contact moved x by `corr` (its normal push d = |corr|): the
// tangential part of the substep's displacement x - x_prev is removed where it is at most mu d (sticking), else
// shortened by mu d (sliding). Over a substep's iterations the pushes add up to the normal impulse over m / dt, so
// the friction adds up to mu times it: a sphere on a slope of angle a slides with g (sin a - mu cos a), or stays.
template <typename T>
INC_HD Vec3<T> coulombAfterContact(const Vec3<T>& x, const Vec3<T>& corr, const Vec3<T>& x_prev, T mu) {
  const T d = norm(corr);
  if (!(mu > T(0)) || !(d > T(0))) return x;
  const Vec3<T> n = corr * (T(1) / d);
  const Vec3<T> dx = x - x_prev;
  const Vec3<T> t = dx - n * dot(dx, n);
  const T lt = norm(t), lim = mu * d;
  return lt <= lim ? x - t : x - t * (lim / lt);
}

// The parameter s in [0, 1] of the point a + s (b - a) of segment a-b closest to x.
template <typename T>
INC_HD T closestSegmentParameter(const Vec3<T>& x, const Vec3<T>& a, const Vec3<T>& b) {
  const Vec3<T> ab = b - a;
  const T l2 = norm2(ab);
  const T t = l2 > T(0) ? dot(x - a, ab) / l2 : T(0);
  return t < T(0) ? T(0) : (t > T(1) ? T(1) : t);
}

template <typename T>
INC_HD Vec3<T> closestPointOnSegment(const Vec3<T>& x, const Vec3<T>& a, const Vec3<T>& b) {
  return a + (b - a) * closestSegmentParameter(x, a, b);
}

template <typename T>
INC_HD T capsuleDistance(const Vec3<T>& x, const CapsuleCollider<T>& c) {
  return norm(x - closestPointOnSegment(x, c.a, c.b)) - c.radius;
}

template <typename T>
INC_HD Vec3<T> capsuleContact(const Vec3<T>& x, T r, const CapsuleCollider<T>& c) {
  const Vec3<T> q = closestPointOnSegment(x, c.a, c.b);
  const Vec3<T> d = x - q;
  const T dist = norm(d), reach = c.radius + r;
  if (dist >= reach) return Vec3<T>();
  if (dist > T(0)) return d * ((reach - dist) / dist);
  // Centre exactly on the axis: push along a fixed direction perpendicular to the axis (deterministic).
  Vec3<T> axis = c.b - c.a;
  Vec3<T> perp = cross(axis, Vec3<T>(T(1), T(0), T(0)));
  if (!(norm2(perp) > T(0))) perp = cross(axis, Vec3<T>(T(0), T(1), T(0)));
  if (!(norm2(perp) > T(0))) perp = Vec3<T>(T(0), T(0), T(1));
  return perp * (reach / norm(perp));
}

// Coulomb friction of a moving tool after its capsule pushed x by `corr`: coulombAfterContact relative to the tool.
// The tool's surface point under the sphere (the same segment parameter on both poses, which move linearly) moved
// by q(t) - q(t0) over the substep; the tangential part of the sphere's displacement relative to that point is
// removed where it is at most mu d (sticking: the sphere moves with the tool) or shortened by mu d (sliding). A
// tool that slides along its own axis over a sphere therefore drags it, and one at rest holds it like a static one.
template <typename T>
INC_HD Vec3<T> toolCoulombAfterContact(const Vec3<T>& x, const Vec3<T>& corr, const Vec3<T>& x_prev,
                                       const CapsuleCollider<T>& at_t0, const CapsuleCollider<T>& at_t) {
  if (!(at_t.friction > T(0)) || !(norm2(corr) > T(0))) return x;
  const T s = closestSegmentParameter(x, at_t.a, at_t.b);
  const Vec3<T> moved = (at_t.a + (at_t.b - at_t.a) * s) - (at_t0.a + (at_t0.b - at_t0.a) * s);
  return coulombAfterContact(x, corr, x_prev + moved, at_t.friction);
}

}  // namespace inc::pbd
