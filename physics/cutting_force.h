// Haptic cutting force model (metaballs-mls-dissection eqs. 15-16): force split, cut state machine, friction.
#pragma once

#include "physics/vec3.h"

namespace inc {

// Tissue thresholds of one material, newtons; friction slope in newtons per metre of blade depth.
template <typename T>
struct CutThresholds {
  T press_n = T(1.0);                       // F_p: the blade enters the tissue when |f_n| > F_p
  T static_n = T(0.6);                      // F_s: cutting starts when |f_t| > F_s (static friction of the tissue)
  T dynamic_n = T(0.3);                     // F_d: cutting stops when |f_t| < F_d (dynamic friction), F_d < F_s
  T friction_per_depth_n_per_m = T(200.0);  // |friction| = k * depth while cutting
};

template <typename T>
struct ForceSplit {
  Vec3<T> normal;      // f_n, along the surface normal
  Vec3<T> tangential;  // f_t, in the tangent plane
};

// eq. 15: f = f_t + f_n with f_n = (f . n) n for the unit surface normal n.
template <typename T>
INC_HD ForceSplit<T> decomposeForce(const Vec3<T>& f, const Vec3<T>& unit_normal) {
  ForceSplit<T> s;
  s.normal = unit_normal * dot(f, unit_normal);
  s.tangential = f - s.normal;
  return s;
}

enum class CutState : int { kIdle = 0, kPressing = 1, kCutting = 2, kStopped = 3 };

struct CutMachine {
  CutState state = CutState::kIdle;
  bool entered = false;    // latched once |f_n| > F_p during this contact
  bool start_cut = false;  // event of the last transition: cutting began (drives the cutting pipeline)
  bool stop_cut = false;   // event of the last transition: cutting ended
};

// One haptic tick of the eq. 16 state machine. idle -> pressing on contact; the blade enters when
// |f_n| > F_p; pressing/stopped -> cutting when entered and |f_t| > F_s; cutting -> stopped when
// |f_t| < F_d (hysteresis band F_d <= |f_t| <= F_s keeps the current state); leaving contact -> idle.
template <typename T>
INC_HD CutMachine cutTransition(CutMachine m, bool in_contact, T fn_mag, T ft_mag, const CutThresholds<T>& th) {
  m.start_cut = m.stop_cut = false;
  if (!in_contact) {
    m.stop_cut = m.state == CutState::kCutting;
    m.state = CutState::kIdle;
    m.entered = false;
    return m;
  }
  if (m.state == CutState::kIdle) m.state = CutState::kPressing;
  if (fn_mag > th.press_n) m.entered = true;
  if (m.state == CutState::kCutting) {
    if (ft_mag < th.dynamic_n) {
      m.state = CutState::kStopped;
      m.stop_cut = true;
    }
  } else if (m.entered && ft_mag > th.static_n) {
    m.state = CutState::kCutting;
    m.start_cut = true;
  }
  return m;
}

// Friction on the blade while cutting: opposite to the tangential blade velocity, magnitude
// k * depth (N/m times m). Zero when the blade does not move tangentially (|v_t| <= v_eps) or is out.
template <typename T>
INC_HD Vec3<T> cuttingFriction(const Vec3<T>& velocity, const Vec3<T>& unit_normal, T depth_m,
                               T friction_per_depth_n_per_m, T v_eps = T(1e-6)) {
  if (depth_m <= T(0)) return Vec3<T>();
  const Vec3<T> vt = velocity - unit_normal * dot(velocity, unit_normal);
  const T s = norm(vt);
  if (s <= v_eps) return Vec3<T>();
  return vt * (-friction_per_depth_n_per_m * depth_m / s);
}

}  // namespace inc
