// Quaternions and the rotation extraction (polar decomposition) used by shape matching and skinning.
#pragma once

#include <cmath>

#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc::pbd {

template <typename T>
struct Quat {
  T w = T(1), x = T(0), y = T(0), z = T(0);
};

template <typename T>
INC_HD Quat<T> quatMul(const Quat<T>& a, const Quat<T>& b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

template <typename T>
INC_HD Quat<T> quatNormalized(const Quat<T>& q) {
  const T n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(n > T(0))) return Quat<T>{};
  const T s = T(1) / n;
  return {q.w * s, q.x * s, q.y * s, q.z * s};
}

// Rotation of `angle` radians about the unit axis `a`.
template <typename T>
INC_HD Quat<T> quatFromAxisAngle(const Vec3<T>& a, T angle) {
  const T h = T(0.5) * angle, s = std::sin(h);
  return {std::cos(h), a.x * s, a.y * s, a.z * s};
}

template <typename T>
INC_HD Mat3<T> quatToMatrix(const Quat<T>& q) {
  Mat3<T> r;
  const T xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
  const T xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z, wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
  r.m[0][0] = T(1) - T(2) * (yy + zz);
  r.m[0][1] = T(2) * (xy - wz);
  r.m[0][2] = T(2) * (xz + wy);
  r.m[1][0] = T(2) * (xy + wz);
  r.m[1][1] = T(1) - T(2) * (xx + zz);
  r.m[1][2] = T(2) * (yz - wx);
  r.m[2][0] = T(2) * (xz - wy);
  r.m[2][1] = T(2) * (yz + wx);
  r.m[2][2] = T(1) - T(2) * (xx + yy);
  return r;
}

// One step of extractRotation below: rotates q towards A's rotational part; false (q unchanged) when the step
// is below eps (converged, or a degenerate A). `scale` is |A|_F (> 0), the same for every step.
// cpu_fallback/pbd_rotation_lanes.h runs this step for four clusters in SIMD lanes (the CPU solver) with the same
// templates in the same order: change both together (tests PbdRotationLanes.* compare them bit for bit).
template <typename T>
INC_HD bool extractRotationStep(const Mat3<T>& a, T scale, Quat<T>& q) {
  const T eps = sizeof(T) == 4 ? T(1e-6) : T(1e-12);
  const Mat3<T> r = quatToMatrix(q);
  Vec3<T> omega = cross(r.col(0), a.col(0)) + cross(r.col(1), a.col(1)) + cross(r.col(2), a.col(2));
  const T denom = std::fabs(dot(r.col(0), a.col(0)) + dot(r.col(1), a.col(1)) + dot(r.col(2), a.col(2)));
  omega *= T(1) / (denom + eps * scale);
  const T angle = norm(omega);
  if (!(angle > eps)) return false;
  q = quatNormalized(quatMul(quatFromAxisAngle(omega * (T(1) / angle), angle), q));
  return true;
}

// Rotational part R of A = R S (polar decomposition), by the iterative quaternion method of Mueller et al.
// 2016 ("A robust method to extract the rotational part of deformations"): each step rotates the current
// estimate about omega = sum_k r_k x a_k / |sum_k r_k . a_k| (r_k, a_k columns of R and A), which
// maximises tr(R^T A). Warm-started from the previous rotation `q`, so a few steps suffice per frame; it
// never produces a reflection, and a degenerate A (flat or collapsed neighbourhood) leaves q unchanged
// in the directions A does not determine. Returns the updated quaternion.
template <typename T>
INC_HD Quat<T> extractRotation(const Mat3<T>& a, Quat<T> q, int max_iterations) {
  const T scale = frobeniusNorm(a);
  if (!(scale > T(0))) return q;  // A == 0: nothing determines a rotation
  for (int it = 0; it < max_iterations; ++it)
    if (!extractRotationStep(a, scale, q)) break;
  return q;
}

// extractRotation of count <= kMaxRotationBatch independent matrices, in lockstep: each gets exactly the steps
// (and result) of its own call, but the steps of different matrices are interleaved, so that a CPU core overlaps
// their dependent chains (each step waits on the previous one's square roots, divisions and sincos; one
// matrix alone leaves the core mostly idle).
constexpr int kMaxRotationBatch = 8;

template <typename T>
INC_HD void extractRotations(const Mat3<T>* a, Quat<T>* q, int count, int max_iterations) {
  T scale[kMaxRotationBatch];
  bool live[kMaxRotationBatch];
  for (int k = 0; k < count; ++k) {
    scale[k] = frobeniusNorm(a[k]);
    live[k] = scale[k] > T(0);
  }
  for (int it = 0; it < max_iterations; ++it)
    for (int k = 0; k < count; ++k)
      if (live[k]) live[k] = extractRotationStep(a[k], scale[k], q[k]);
}

}  // namespace inc::pbd
