// Quartic spline MLS weight of the method of finite spheres (eq. 2-3) and the singular tool-tip weight (eq. 5).
#pragma once

#include "physics/vec3.h"

namespace inc {

// w(s) = 1 - 6 s^2 + 8 s^3 - 3 s^4 for s = r / rho in [0, 1], 0 beyond: C1 at s = 1, w(0) = 1.
template <typename T>
INC_HD T quarticSpline(T s) {
  if (s >= T(1)) return T(0);
  const T s2 = s * s;
  return T(1) - T(6) * s2 + T(8) * s2 * s - T(3) * s2 * s2;
}
// dw/ds = -12 s + 24 s^2 - 12 s^3 = -12 s (1 - s)^2.
template <typename T>
INC_HD T quarticSplineDs(T s) {
  if (s >= T(1)) return T(0);
  return T(-12) * s * (T(1) - s) * (T(1) - s);
}

// Weight of node J at x and its gradient (1/m). rho_m: radius of the node's sphere. singular_p > 0
// multiplies by (r / rho)^-p (eq. 5): the weight blows up at the node so that the MLS approximation
// interpolates there (h_J(x_J) = 1, the prescribed tool-tip displacement holds exactly). Requires r > 0
// when singular_p > 0 (quadrature points never coincide with nodes).
template <typename T>
INC_HD T mfsWeight(const Vec3<T>& x, const Vec3<T>& node, T rho_m, int singular_p, Vec3<T>* grad) {
  const Vec3<T> d = x - node;
  const T r = norm(d);
  const T s = r / rho_m;
  T w = quarticSpline(s);
  if (w == T(0)) {
    if (grad) *grad = Vec3<T>();
    return T(0);
  }
  // dw/dx = w'(s) d / (r rho); w'(s)/s = -12 (1 - s)^2 stays finite at r = 0.
  Vec3<T> g = d * (T(-12) * (T(1) - s) * (T(1) - s) / (rho_m * rho_m));
  if (singular_p > 0) {
    T sp = T(1);
    for (int k = 0; k < singular_p; ++k) sp *= s;  // s^p
    const T inv = T(1) / sp;
    g = g * inv + d * (-T(singular_p) * w * inv / (r * r));
    w *= inv;
  }
  if (grad) *grad = g;
  return w;
}

}  // namespace inc
