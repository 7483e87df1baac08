// The CPU's rotation extraction of up to four shape-matching clusters at once, one cluster per SSE2 lane
// (pbd::extractRotations' results, bit for bit).
#pragma once

#include <cmath>
#include <cstdint>

#include "cpu_fallback/simd_lanes.h"
#include "physics/pbd_rotation.h"

namespace inc::cpu {

// Clusters whose extractions RotationLanes runs side by side (the CPU solver's batch of clusters).
constexpr int kRotationLaneBatch = 4;

#if defined(INC_HAVE_SIMD_LANES)
#define INC_HAVE_ROTATION_LANES 1

// Why a second copy of pbd::extractRotationStep exists: the CPU projects shape-matching clusters four at a time, and
// one cluster's step is a dependent chain of scalar operations (two square roots, three divisions, a sincos); on the
// liver-sized model the extractions took ~26 M of the frame's ~133 M instructions. Four clusters in the four lanes of
// one register do the same work in less than half the instructions. The GPU keeps the scalar function (one cluster
// per thread group). To keep one formula, the lane version calls the very templates the scalar step calls
// (quatToMatrix, cross, dot, quatMul, the Vec3 and Mat3 operators) with a lane type whose operators are the same IEEE
// operations lane by lane: _mm_div_ps and _mm_sqrt_ps round correctly as '/' and sqrtf do (no rsqrt / rcp
// estimates), and the build has no FMA, so every lane gets the scalar step's bits. What the scalar step writes as
// branches (a converged or degenerate cluster stops; quatNormalized of a zero quaternion is the identity) becomes a
// per-lane select. The sine and cosine stay scalar calls per lane (std::sin / std::cos, as quatFromAxisAngle makes
// them): a vector polynomial would not give libm's bits. A change to the scalar step must be made here too; the
// tests PbdRotationLanes.* compare the two bit for bit (random, zero, reflected, near-singular and non-finite
// matrices; whole frames).

// std::sin and std::cos of h in the lanes of `on` (the calls quatFromAxisAngle makes, so the same bits); the other
// lanes get sin 0, cos 1 and are not used.
template <class L>
inline void sinCosLanes(L h, typename L::Mask on, L& s, L& c) {
  using T = typename L::Scalar;
  alignas(16) T hv[L::kWidth], sv[L::kWidth], cv[L::kWidth];
  h.store(hv);
  for (int k = 0; k < L::kWidth; ++k) {
    sv[k] = T(0);
    cv[k] = T(1);
    if (on.lane(k)) {
      sv[k] = std::sin(hv[k]);
      cv[k] = std::cos(hv[k]);
    }
  }
  s = L::load(sv);
  c = L::load(cv);
}

// pbd::extractRotationStep for a lane's cluster each, line by line (see there for the method): lanes not in `live`
// keep q; returns the lanes that stepped (where the scalar step returns true). eps_scale = eps |A|_F, the product
// the scalar step forms each time (the same bits).
template <class L>
inline typename L::Mask extractRotationStepLanes(const Mat3<L>& a, L eps_scale, pbd::Quat<L>& q,
                                                 typename L::Mask live) {
  using T = typename L::Scalar;
  const L eps(sizeof(T) == 4 ? T(1e-6) : T(1e-12));
  const Mat3<L> r = pbd::quatToMatrix(q);
  Vec3<L> omega = cross(r.col(0), a.col(0)) + cross(r.col(1), a.col(1)) + cross(r.col(2), a.col(2));
  const L denom = abs(dot(r.col(0), a.col(0)) + dot(r.col(1), a.col(1)) + dot(r.col(2), a.col(2)));
  omega *= L(T(1)) / (denom + eps_scale);
  const L angle = sqrt(dot(omega, omega));             // norm(omega)
  const typename L::Mask step = live & (angle > eps);  // the scalar step's `if (!(angle > eps)) return false`
  if (!step.any()) return step;
  // quatFromAxisAngle(omega * (1 / angle), angle)
  const Vec3<L> axis = omega * (L(T(1)) / angle);
  L s, c;
  sinCosLanes(L(T(0.5)) * angle, step, s, c);
  const pbd::Quat<L> m = pbd::quatMul(pbd::Quat<L>{c, axis.x * s, axis.y * s, axis.z * s}, q);
  // quatNormalized(m): the identity where |m| is not > 0
  const L n = sqrt(m.w * m.w + m.x * m.x + m.y * m.y + m.z * m.z);
  const typename L::Mask unit = n > L(T(0));
  const L inv = L(T(1)) / n;
  q.w = select(step, select(unit, m.w * inv, L(T(1))), q.w);
  q.x = select(step, select(unit, m.x * inv, L(T(0))), q.x);
  q.y = select(step, select(unit, m.y * inv, L(T(0))), q.y);
  q.z = select(step, select(unit, m.z * inv, L(T(0))), q.z);
  return step;
}

// The extractions of up to kRotationLaneBatch clusters, cluster k in lane k, advanced one lockstep step at a time:
// start, then step() until it returns false or max_iterations steps were taken, then finish. Each cluster gets the
// steps and the result of its own pbd::extractRotation (one with A = 0 is not stepped; one stops at its first step
// below eps). Split into steps so that the CPU solver can issue a step between other work (the steps are a
// dependent chain; the core runs independent work beside it). float: one register of 4 lanes; double: two of 2,
// stepped one after the other.
template <class L>
class RotationLanes {
 public:
  using T = typename L::Scalar;

  void start(const Mat3<T>* a, const pbd::Quat<T>* q, int count) {
    // Padding lanes: the zero matrix (never stepped) and the identity.
    Mat3<T> a_pad[kRotationLaneBatch];
    pbd::Quat<T> q_pad[kRotationLaneBatch];
    if (count < kRotationLaneBatch) {
      for (int k = 0; k < kRotationLaneBatch; ++k) {
        a_pad[k] = k < count ? a[k] : Mat3<T>();
        q_pad[k] = k < count ? q[k] : pbd::Quat<T>{};
      }
      a = a_pad;
      q = q_pad;
    }
    const T eps = sizeof(T) == 4 ? T(1e-6) : T(1e-12);
    for (int g = 0; g < G; ++g) {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) a_[g].m[r][c] = L::gather(&a[g * W].m[r][c], int(sizeof(Mat3<T>) / sizeof(T)));
      constexpr int qs = int(sizeof(pbd::Quat<T>) / sizeof(T));
      q_[g] = {L::gather(&q[g * W].w, qs), L::gather(&q[g * W].x, qs), L::gather(&q[g * W].y, qs),
               L::gather(&q[g * W].z, qs)};
      // frobeniusNorm: ddot's sum in its order, then the square root.
      L ss(T(0));
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) ss += a_[g].m[r][c] * a_[g].m[r][c];
      const L scale = sqrt(ss);
      eps_scale_[g] = L(eps) * scale;
      live_[g] = L::lanesBelow(count - g * W) & (scale > L(T(0)));  // extractRotations: live while scale > 0
    }
  }

  // One step of every live cluster; false when none stepped (then none is live: further steps change nothing).
  bool step() {
    bool any = false;
    for (int g = 0; g < G; ++g) {
      if (!live_[g].any()) continue;
      live_[g] = extractRotationStepLanes(a_[g], eps_scale_[g], q_[g], live_[g]);
      any = any || live_[g].any();
    }
    return any;
  }

  void finish(pbd::Quat<T>* q, int count) const {
    for (int g = 0; g < G; ++g) {
      alignas(16) T qv[4][W];
      q_[g].w.store(qv[0]);
      q_[g].x.store(qv[1]);
      q_[g].y.store(qv[2]);
      q_[g].z.store(qv[3]);
      for (int k = 0; k < W && g * W + k < count; ++k)
        q[g * W + k] = pbd::Quat<T>{qv[0][k], qv[1][k], qv[2][k], qv[3][k]};
    }
  }

 private:
  static constexpr int W = L::kWidth, G = kRotationLaneBatch / W;
  static_assert(G * W == kRotationLaneBatch, "whole registers");
  Mat3<L> a_[G];
  pbd::Quat<L> q_[G];
  L eps_scale_[G];
  typename L::Mask live_[G];
};

// pbd::extractRotations(a, q, count, max_iterations) for count <= kRotationLaneBatch clusters, in lanes.
template <class L>
inline void extractRotationsLanes(const Mat3<typename L::Scalar>* a, pbd::Quat<typename L::Scalar>* q, int count,
                                  int max_iterations) {
  RotationLanes<L> r;
  r.start(a, q, count);
  for (int it = 0; it < max_iterations; ++it)
    if (!r.step()) break;
  r.finish(q, count);
}

// The lane type of a scalar type.
template <typename T>
struct RotationLanesOf;
template <>
struct RotationLanesOf<float> {
  using type = F32x4;
};
template <>
struct RotationLanesOf<double> {
  using type = F64x2;
};
#endif

}  // namespace inc::cpu
