// Per-tick haptic force safety: magnitude clamp, force-rate limiter, fade-out on a stalled simulation.
#pragma once

#include "physics/vec3.h"

namespace inc {

// Scales f so that |f| <= max_n (newtons), keeping its direction. Non-finite input gives zero force.
template <typename T>
INC_HD Vec3<T> clampForce(const Vec3<T>& f, T max_n) {
  if (!isFinite(f)) return Vec3<T>();
  const T m = norm(f);
  return m > max_n ? f * (max_n / m) : f;
}

// Moves from the previous output towards the target by at most max_rate_n_per_s * dt_s (newtons per
// second times seconds): a jump in the model's force becomes a ramp the device can render stably.
template <typename T>
INC_HD Vec3<T> rateLimitForce(const Vec3<T>& previous, const Vec3<T>& target, T max_rate_n_per_s, T dt_s) {
  const Vec3<T> step = target - previous;
  const T m = norm(step);
  const T max_step = max_rate_n_per_s * dt_s;
  return m > max_step ? previous + step * (max_step / m) : target;
}

// Gain for a force computed from simulation data that is age_s old: 1 while age <= stall_after_s, then
// a linear fade to 0 over fade_s, so a stalled simulation releases the hand instead of freezing a force.
template <typename T>
INC_HD T stallFadeGain(T age_s, T stall_after_s, T fade_s) {
  if (age_s <= stall_after_s) return T(1);
  if (fade_s <= T(0)) return T(0);
  const T g = T(1) - (age_s - stall_after_s) / fade_s;
  return g > T(0) ? g : T(0);
}

}  // namespace inc
