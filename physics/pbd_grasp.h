// Grasp geometry: which spheres a closing grasper's jaws catch, and where a caught sphere is held.
#pragma once

#include "physics/distance.h"
#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc::pbd {

// A sphere (centre x, radius r) is caught when it touches the jaw ball of radius `reach` around the tip:
// |x - tip| <= reach + r (decided with distance2Exact so both backends and the host agree).
template <typename T>
INC_HD bool inGraspReach(const Vec3<T>& x, T r, const Vec3<T>& tip, T reach) {
  const T d = reach + r;
  return distance2Exact(x, tip) <= d * d;
}

// Where a caught sphere is held: its offset from the tip at the moment of the grasp, carried along by the
// tip (the jaws translate with the tool; the grasp axis's rotation is not applied to the offsets).
template <typename T>
INC_HD Vec3<T> graspTarget(const Vec3<T>& tip, const Vec3<T>& offset) {
  return tip + offset;
}

}  // namespace inc::pbd
