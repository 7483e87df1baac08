// The scene's static colliders (planes, boxes) as contacts for MLS nodal points: a point that ends a drift inside one
// is put back on its surface and loses the velocity that carries it in (inelastic), with the collider's Coulomb
// friction on the velocity along it.
#pragma once

#include "physics/hd.h"
#include "physics/mls_contact_velocity.h"
#include "physics/pbd_collision.h"
#include "physics/vec3.h"

namespace inc {

// The colliders in the points' frame (relative to the model origin). Fixed-size so that one small upload carries
// them and a kernel reads them without a second indirection; scenes are refused beyond kMax of a kind.
template <typename T>
struct MlsStaticContacts {
  static constexpr int kMax = 8;
  pbd::PlaneCollider<T> planes[kMax];
  pbd::BoxCollider<T> boxes[kMax];
  int planes_n = 0, boxes_n = 0;
  T radius = T(0);  // m: a point meets the colliders this far from its centre (half the sampling spacing: the
                    // surface the lattice samples lies that far beyond its outermost points)
};

// Particle k after its drift: each collider in turn (planes, then boxes, as pbd::resolveContacts orders a sphere's)
// moves x = X + u out along the contact normal (the point is a ball of c.radius: pbd::planeContact /
// pbd::boxContact give the correction) and removes the velocity's inward normal component, dv_n; friction mu then
// takes at most mu dv_n from the tangential velocity (the impulse limit of a point mass, as the blade's contact:
// physics/mls_blade_contact.h), and the same share of the drift it made along the collider (v is the drift's
// velocity, dt its step): a velocity-only friction let a sticking block creep by that drift every substep (2.5 mm/s
// on a 20 degree slope). A point outside every collider is unchanged bit for bit.
template <typename T>
INC_HD void mlsStaticContactAt(const MlsStaticContacts<T>& c, const Vec3<T>& rest, Vec3<T>& u, Vec3<T>& v, T dt) {
  const auto apply = [&](const Vec3<T>& corr, T mu) {
    const T len = norm(corr);
    if (!(len > T(0))) return;
    u += corr;
    Vec3<T> friction_dv;
    if (mlsContactVelocity(v, Vec3<T>(), corr * (T(1) / len), mu, friction_dv)) u -= friction_dv * dt;
  };
  for (int k = 0; k < c.planes_n; ++k) apply(pbd::planeContact(rest + u, c.radius, c.planes[k]), c.planes[k].friction);
  for (int k = 0; k < c.boxes_n; ++k) apply(pbd::boxContact(rest + u, c.radius, c.boxes[k]), c.boxes[k].friction);
}

}  // namespace inc
