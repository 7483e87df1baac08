// A nodal point's velocity at a contact it was just put on (the blade's, a static collider's): inelastic along the
// contact normal, Coulomb friction along it.
#pragma once

#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc {

// `v` relative to the contact's own velocity `w` (0 for a static collider), `n` the unit outward normal: where v
// moves into the contact, its normal component dv_n is removed and friction mu takes at most mu dv_n from the
// tangential one (the Coulomb impulse limit for a point mass); that friction change is returned (zero without
// friction). Returns false, v unchanged, where v does not move into the contact.
template <typename T>
INC_HD bool mlsContactVelocity(Vec3<T>& v, const Vec3<T>& w, const Vec3<T>& n, T mu, Vec3<T>& friction_dv) {
  const T vn = dot(v - w, n);
  if (!(vn < T(0))) return false;
  v -= n * vn;
  friction_dv = Vec3<T>();
  if (!(mu > T(0))) return true;
  const Vec3<T> vt = v - w - n * dot(v - w, n);  // relative, tangential (the normal part is zero up to rounding)
  const T st = norm(vt), slip = mu * (-vn);
  friction_dv = st > slip ? vt * (slip / st) : vt;
  v -= friction_dv;
  return true;
}

}  // namespace inc
