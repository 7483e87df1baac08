// CUDA projection of the cluster constraints (shape matching, Laplacian) by a group of lanes per constraint.
#pragma once

#include <cstdint>

#include "physics/pbd_block.h"

namespace inc::cuda::pbdgroup {

// Lanes per cluster: a sphere of the liver-sized organ has ~14 neighbours, so one member per lane. A cluster
// projected by one thread is a serial chain of ~4 passes of dependent gathers over its members (the GPU frame
// was latency bound on it); a group runs those passes member-parallel and sums with shuffles.
constexpr int kGroup = 16;

// Does this block kind take the group projection?
inline __host__ __device__ bool usesGroup(int kind) { return kind == pbd::kShapeMatching || kind == pbd::kLaplacian; }

// Sum over the kGroup lanes of a group, as a fixed xor-butterfly (every lane gets the same, deterministic
// result). Every lane of the warp must call it (full-warp mask): groups with no constraint contribute zeros.
template <typename T>
__device__ inline T groupSum(T v) {
  for (int off = kGroup / 2; off > 0; off >>= 1) v += __shfl_xor_sync(0xffffffffu, v, off);
  return v;
}
template <typename T>
__device__ inline Vec3<T> groupSum(Vec3<T> v) {
  return Vec3<T>(groupSum(v.x), groupSum(v.y), groupSum(v.z));
}
template <typename T>
__device__ inline Mat3<T> groupSum(Mat3<T> a) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a.m[r][c] = groupSum(a.m[r][c]);
  return a;
}

// Shape matching of cluster c (valid == false: this group only takes part in the shuffles). The same terms
// as the serial case of pbd::projectConstraint: the cluster frame (clusterFrame's sums), the rotation, the
// momentum pass and the apply pass (physics/pbd_block.h).
template <typename T>
__device__ void shapeMatchingGroup(const pbd::BlockView<T>& b, int c, bool valid, const pbd::SolveContext<T>& ctx,
                                   int lane) {
  const std::int32_t s0 = valid ? b.offsets[c] : 0, s1 = valid ? b.offsets[c + 1] : 0;
  Vec3<T> mx;
  T ms = T(0);
  for (std::int32_t s = s0 + lane; s < s1; s += kGroup) {
    const std::int32_t p = b.ids[s];
    mx += ctx.x[p] * ctx.mass[p];
    ms += ctx.mass[p];
  }
  mx = groupSum(mx);
  ms = groupSum(ms);
  const Vec3<T> x_cm = ms > T(0) ? mx * (T(1) / ms) : mx;
  Mat3<T> a;
  for (std::int32_t s = s0 + lane; s < s1; s += kGroup) {
    const std::int32_t p = b.ids[s];
    a += outer(ctx.x[p] - x_cm, b.rest_vec[s]) * ctx.mass[p];
  }
  a = groupSum(a);
  // Every lane reads the warm start before lane 0 stores the new rotation (no lane may see the update).
  const std::int32_t centre = valid ? b.ids[s0] : 0;
  pbd::Quat<T> q{};
  if (valid) q = ctx.rotation[centre];
  __syncwarp();
  if (valid) {
    q = pbd::extractRotation(a, q, ctx.rotation_iterations);
    if (lane == 0) ctx.rotation[centre] = q;
  }
  const Mat3<T> rot = pbd::quatToMatrix(q);
  // Each lane keeps the goal of its first member from pass 1 for pass 2 (a member's goal depends only on its own
  // position and the cluster frame, which pass 1 does not change); members beyond the first kGroup (clusters
  // larger than the group) compute theirs again.
  Vec3<T> dmom;
  T mov_mass = T(0);
  pbd::GoalCorrection<T> first{};
  for (std::int32_t s = s0 + lane; s < s1; s += kGroup) {
    const pbd::GoalCorrection<T> g = pbd::shapeMatchGoal(b, ctx, s, rot, x_cm);
    if (s == s0 + lane) first = g;
    pbd::shapeMatchMomentumTerm(b, ctx, s, g, dmom, mov_mass);
  }
  dmom = groupSum(dmom);
  mov_mass = groupSum(mov_mass);
  const Vec3<T> shift = pbd::shapeMatchShift(dmom, mov_mass);
  for (std::int32_t s = s0 + lane; s < s1; s += kGroup)
    pbd::shapeMatchApplyTerm(b, ctx, s, s == s0 + lane ? first : pbd::shapeMatchGoal(b, ctx, s, rot, x_cm), shift);
}

// Laplacian-coordinate constraint c: the neighbour sums by the group, the correction by pbd::laplacianFromSums.
template <typename T>
__device__ void laplacianGroup(const pbd::BlockView<T>& b, int c, bool valid, const pbd::SolveContext<T>& ctx,
                               int lane) {
  const std::int32_t s0 = valid ? b.offsets[c] : 0, s1 = valid ? b.offsets[c + 1] : 0;
  Vec3<T> mean_sum;
  T wn = T(0);
  for (std::int32_t s = s0 + 1 + lane; s < s1; s += kGroup) {
    mean_sum += ctx.x[b.ids[s]];
    wn += ctx.w[b.ids[s]];
  }
  mean_sum = groupSum(mean_sum);
  wn = groupSum(wn);
  pbd::LaplacianCorrection<T> r;
  T scale = T(1);
  if (valid) {
    const std::int32_t centre = b.ids[s0];
    const pbd::XpbdTerm<T> term = pbd::xpbdTerm(ctx.xpbd, b.compliance[c], b.stiffness, ctx.dt);
    r = pbd::laplacianFromSums(ctx.x[centre], ctx.w[centre], mean_sum, wn, int(s1 - s0), pbd::laplacianRest(b, c, ctx),
                               term, b.lambda[c]);
    scale = pbd::slotScale(b, ctx, s0);
  }
  __syncwarp();        // every lane has read x and lambda before any lane writes them (Gauss-Seidel writes in place)
  if (!valid) return;  // a lone centre (count < 2) still writes its zero correction, as the serial case does
  if (lane == 0) {
    pbd::emitCorrection(b, ctx, s0, r.d_center, scale);
    b.lambda[c] += r.dlambda * scale;
  }
  for (std::int32_t s = s0 + 1 + lane; s < s1; s += kGroup)
    pbd::emitCorrection(b, ctx, s, r.dlambda * (-ctx.w[b.ids[s]] * r.inv_n), scale);
}

// Constraint c of a group kind (the caller checked usesGroup(b.kind)).
template <typename T>
__device__ inline void projectGroup(const pbd::BlockView<T>& b, int c, bool valid, const pbd::SolveContext<T>& ctx,
                                    int lane) {
  if (b.kind == pbd::kShapeMatching)
    shapeMatchingGroup(b, c, valid, ctx, lane);
  else
    laplacianGroup(b, c, valid, ctx, lane);
}

}  // namespace inc::cuda::pbdgroup
