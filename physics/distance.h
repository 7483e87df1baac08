// Squared distance computed bit-identically on host and device (no FMA contraction on either side).
#pragma once

#include "physics/hd.h"
#include "physics/vec3.h"

namespace inc {

// Neighbour decisions (d^2 <= r^2) must agree exactly between backends; nvcc contracts a*b+c into FMA
// by default, so the device path uses round-to-nearest intrinsics that are never fused.
INC_HD float distance2Exact(const Vec3f& a, const Vec3f& b) {
  const float dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
#if defined(__CUDA_ARCH__)
  return __fadd_rn(__fadd_rn(__fmul_rn(dx, dx), __fmul_rn(dy, dy)), __fmul_rn(dz, dz));
#else
  volatile float xx = dx * dx, yy = dy * dy, zz = dz * dz;  // volatile: keep the host from fusing too
  return (xx + yy) + zz;
#endif
}

INC_HD double distance2Exact(const Vec3d& a, const Vec3d& b) {
  const double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
#if defined(__CUDA_ARCH__)
  return __dadd_rn(__dadd_rn(__dmul_rn(dx, dx), __dmul_rn(dy, dy)), __dmul_rn(dz, dz));
#else
  volatile double xx = dx * dx, yy = dy * dy, zz = dz * dz;
  return (xx + yy) + zz;
#endif
}

}  // namespace inc
