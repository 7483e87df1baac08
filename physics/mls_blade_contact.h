// The scalpel's capsule as a contact for MLS nodal points: a point the moving blade covers is put back on its surface
// and loses the velocity that carries it into the blade (inelastic, with Coulomb friction), inside each substep's
// drift.
#pragma once

#include "physics/hd.h"
#include "physics/mls_contact_velocity.h"
#include "physics/vec3.h"

namespace inc {

// The blade over one solver advance (rest positions' frame: relative to the model origin): the segment moves
// linearly from (a0, b0) to (a1, b1) over `duration` seconds in `substeps` equal substeps. radius 0: no contact.
template <typename T>
struct MlsBladeContact {
  Vec3<T> a0, b0, a1, b1;  // m
  T radius = T(0);         // m
  T duration = T(0);       // s, > 0 where radius > 0
  int substeps = 1;
  T friction = T(0);  // Coulomb coefficient mu >= 0 (0: frictionless)
};

// Particle k after its drift in the substep with `remaining` substeps left (this one included): where its current
// position x = X + u lies within `radius` of the blade's segment at the end of that substep, x moves along the
// outward normal onto the capsule and the velocity's component into the blade, relative to the blade's own velocity
// there, is removed. Friction: that normal velocity change dv_n, times mu, is taken from the relative tangential
// velocity v_t (the Coulomb impulse limit for a point mass, dv_t <= mu dv_n): v_t scales by
// max(0, 1 - mu dv_n / |v_t|), so a point slides along the blade more slowly or, where mu dv_n >= |v_t|, moves with
// it. Outside the capsule, or moving out of it, nothing changes (bit for bit).
template <typename T>
INC_HD void mlsBladeContactAt(const MlsBladeContact<T>& c, const Vec3<T>& rest, Vec3<T>& u, Vec3<T>& v, int remaining) {
  const T f = T(c.substeps - remaining + 1) / T(c.substeps);
  const Vec3<T> a = c.a0 + (c.a1 - c.a0) * f, b = c.b0 + (c.b1 - c.b0) * f;
  const Vec3<T> x = rest + u;
  const Vec3<T> ab = b - a;
  const T len2 = norm2(ab);
  T t = len2 > T(0) ? dot(x - a, ab) / len2 : T(0);
  t = t < T(0) ? T(0) : (t > T(1) ? T(1) : t);
  const Vec3<T> q = a + ab * t;
  Vec3<T> d = x - q;
  // Beside the segment's interior the offset is perpendicular to it; remove the rounding's axial part, which would
  // otherwise be the whole normal of a point on the axis.
  if (t > T(0) && t < T(1)) d -= ab * (dot(d, ab) / len2);
  const T dist = norm(d);
  if (dist >= c.radius) return;
  Vec3<T> n;
  if (dist > c.radius * T(1e-6)) {
    n = d * (T(1) / dist);
  } else {  // on the axis: a fixed direction perpendicular to it (deterministic), as pbd::capsuleContact does
    n = cross(ab, Vec3<T>(T(1), T(0), T(0)));
    if (!(norm2(n) > T(0))) n = cross(ab, Vec3<T>(T(0), T(1), T(0)));
    if (!(norm2(n) > T(0))) n = Vec3<T>(T(0), T(0), T(1));
    n = n * (T(1) / norm(n));
  }
  u = q + n * c.radius - rest;
  const Vec3<T> w =
      ((c.a1 - c.a0) * (T(1) - t) + (c.b1 - c.b0) * t) * (T(1) / c.duration);  // the blade's velocity at q
  Vec3<T> friction_dv;
  mlsContactVelocity(v, w, n, c.friction, friction_dv);
}

}  // namespace inc
