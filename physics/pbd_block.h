// One constraint of a block projected from raw arrays (Jacobi slot output or in-place Gauss-Seidel), and the
// per-particle substep steps.
#pragma once

#include <cmath>
#include <cstdint>

#include "physics/hd.h"
#include "physics/pbd_collision.h"
#include "physics/pbd_constraints.h"
#include "physics/pbd_rotation.h"
#include "physics/vec3.h"

namespace inc::pbd {

enum : int { kDistance = 0, kBending = 1, kTetVolume = 2, kLaplacian = 3, kShapeMatching = 4 };

// Raw view of one constraint block (host or device pointers); see model/pbd_model.h for the meaning.
template <typename T>
struct BlockView {
  int kind = kDistance;
  int count = 0;
  T stiffness = T(1);
  const std::int32_t* offsets = nullptr;
  const std::int32_t* ids = nullptr;
  const T* rest = nullptr;
  const Vec3<T>* rest_vec = nullptr;
  const T* compliance = nullptr;
  const T* jacobi_scale = nullptr;
  const std::int32_t* particle_offsets = nullptr;
  const std::int32_t* particle_slots = nullptr;
  Vec3<T>* lambda = nullptr;     // multipliers; scalar kinds use .x
  Vec3<T>* slot_corr = nullptr;  // Jacobi: correction of each slot's particle
  // Optional, per multiplier (as compliance): compliance / dt^2 of this frame's substep, precomputed by a backend
  // that projects a block many times with one dt (the CPU); null: computed from `compliance` at each projection.
  const T* alpha_tilde = nullptr;
};

// What every projection reads besides its block.
template <typename T>
struct SolveContext {
  Vec3<T>* x = nullptr;         // positions (read; written in place by Gauss-Seidel)
  const T* w = nullptr;         // inverse masses of this frame (kinematic particles 0)
  const T* mass = nullptr;      // masses (shape-matching centre of mass)
  Quat<T>* rotation = nullptr;  // per-particle rotation, updated by the particle's own cluster
  bool xpbd = true;
  T dt = T(0);
  bool jacobi = true;
  T omega = T(1);  // Jacobi over-relaxation
  int rotation_iterations = 4;
};

// The XPBD term of multiplier i of a block: xpbdTerm of its compliance, or the same value precomputed.
template <typename T>
INC_HD XpbdTerm<T> blockTerm(const BlockView<T>& b, const SolveContext<T>& ctx, std::int32_t i) {
  if (ctx.xpbd && b.alpha_tilde) {
    XpbdTerm<T> t;
    t.alpha_tilde = b.alpha_tilde[i];
    return t;
  }
  return xpbdTerm(ctx.xpbd, b.compliance[i], b.stiffness, ctx.dt);
}

// Gauss-Seidel writes only movable particles: a fixed one (w = 0, zero correction) may be shared by the
// constraints of one colour (model/graph_coloring.h), which run concurrently, so it is never written.
template <typename T>
INC_HD void emitCorrection(const BlockView<T>& b, const SolveContext<T>& ctx, std::int32_t slot, const Vec3<T>& d,
                           T scale) {
  if (ctx.jacobi)
    b.slot_corr[slot] = d * scale;
  else if (ctx.w[b.ids[slot]] > T(0))
    ctx.x[b.ids[slot]] += d;
}

// ---- Shape matching, split into per-member terms: projectConstraint loops over the members one after another;
// the CUDA group projection (kernels/pbd_group_projection.cuh) gives each member a lane and sums the same
// terms with a fixed-order tree reduction. Same formulas, different loop.

// The cluster's rotation from its moment matrix, warm-started from (and stored as) the centre's rotation.
template <typename T>
INC_HD Mat3<T> shapeMatchRotation(const SolveContext<T>& ctx, std::int32_t centre, const Mat3<T>& a_pq) {
  const Quat<T> q = extractRotation(a_pq, ctx.rotation[centre], ctx.rotation_iterations);
  ctx.rotation[centre] = q;
  return quatToMatrix(q);
}

template <typename T>
INC_HD T slotScale(const BlockView<T>& b, const SolveContext<T>& ctx, std::int32_t s) {
  return ctx.jacobi ? ctx.omega * b.jacobi_scale[s] : T(1);
}

template <typename T>
INC_HD GoalCorrection<T> shapeMatchGoal(const BlockView<T>& b, const SolveContext<T>& ctx, std::int32_t s,
                                        const Mat3<T>& rot, const Vec3<T>& x_cm) {
  const std::int32_t p = b.ids[s];
  const XpbdTerm<T> term = blockTerm(b, ctx, s);
  return projectGoal(ctx.x[p], ctx.w[p], rot * b.rest_vec[s] + x_cm, term, b.lambda[s]);
}

// Pass 1, one member: its share of the net momentum change sum_k m_k dp_k. With equal compliance-to-mass
// ratios the sum is zero (sum_k m_k q_k = 0), but per-member compliances and Jacobi scales differ at the
// boundary; the sum is removed by a uniform shift of the movable members, so internal shape matching never
// creates momentum (the shift is a rigid translation: it does not change the shape error).
// The Term forms take the member's goal correction already computed (a serial loop computes it once for both
// passes: within one projection a member's goal depends only on its own position and the cluster frame).
template <typename T>
INC_HD void shapeMatchMomentumTerm(const BlockView<T>& b, const SolveContext<T>& ctx, std::int32_t s,
                                   const GoalCorrection<T>& r, Vec3<T>& dmom, T& mov_mass) {
  const std::int32_t p = b.ids[s];
  if (!(ctx.w[p] > T(0))) return;
  dmom += r.dp * (slotScale(b, ctx, s) * ctx.mass[p]);
  mov_mass += ctx.mass[p];
}

template <typename T>
INC_HD void shapeMatchMomentum(const BlockView<T>& b, const SolveContext<T>& ctx, std::int32_t s, const Mat3<T>& rot,
                               const Vec3<T>& x_cm, Vec3<T>& dmom, T& mov_mass) {
  if (!(ctx.w[b.ids[s]] > T(0))) return;
  shapeMatchMomentumTerm(b, ctx, s, shapeMatchGoal(b, ctx, s, rot, x_cm), dmom, mov_mass);
}

template <typename T>
INC_HD Vec3<T> shapeMatchShift(const Vec3<T>& dmom, T mov_mass) {
  return mov_mass > T(0) ? dmom * (-T(1) / mov_mass) : Vec3<T>();
}

// Pass 2, one member: its correction (slot output for Jacobi, in place for Gauss-Seidel) and multiplier.
template <typename T>
INC_HD void shapeMatchApplyTerm(const BlockView<T>& b, const SolveContext<T>& ctx, std::int32_t s,
                                const GoalCorrection<T>& r, const Vec3<T>& shift) {
  const std::int32_t p = b.ids[s];
  const T sc = slotScale(b, ctx, s);
  const Vec3<T> d = ctx.w[p] > T(0) ? r.dp * sc + shift : Vec3<T>();
  if (ctx.jacobi)
    b.slot_corr[s] = d;
  else if (ctx.w[p] > T(0))  // a fixed member may belong to another cluster of this colour (emitCorrection)
    ctx.x[p] += d;
  b.lambda[s] += r.dlambda * sc;
}

template <typename T>
INC_HD void shapeMatchApply(const BlockView<T>& b, const SolveContext<T>& ctx, std::int32_t s, const Mat3<T>& rot,
                            const Vec3<T>& x_cm, const Vec3<T>& shift) {
  shapeMatchApplyTerm(b, ctx, s, shapeMatchGoal(b, ctx, s, rot, x_cm), shift);
}

// The Laplacian's rest offset, turned by the centre's rotation when rotations are tracked.
template <typename T>
INC_HD Vec3<T> laplacianRest(const BlockView<T>& b, int c, const SolveContext<T>& ctx) {
  return ctx.rotation ? quatToMatrix(ctx.rotation[b.ids[b.offsets[c]]]) * b.rest_vec[c] : b.rest_vec[c];
}

// One constraint of each kind (projectConstraint below dispatches on the block's kind; a loop over one block
// may call its kind's function directly). Jacobi: corrections (scaled by omega * jacobi_scale) go to slot_corr
// and the multiplier advances by the same scaled amount, so lambda always matches the displacement actually
// applied and XPBD's equilibrium is kept; Gauss-Seidel: positions move in place (the colouring makes that
// race-free).
// The default emitter of the projections below: emitCorrection (slot output for Jacobi, in place for
// Gauss-Seidel). A backend may pass its own for Jacobi (the CUDA kernels stage a block's slots in shared memory
// to store them coalesced); it receives the slot, the particle and the already scaled correction.
template <typename T>
struct EmitToBlock {
  const BlockView<T>& b;
  const SolveContext<T>& ctx;
  INC_HD void operator()(std::int32_t slot, std::int32_t /*particle*/, const Vec3<T>& d, T scale) const {
    emitCorrection(b, ctx, slot, d, scale);
  }
};

// Distance constraint c with its two particle ids given (a backend may load them together).
template <typename T, typename Emit>
INC_HD void projectDistanceConstraintIds(const BlockView<T>& b, int c, const SolveContext<T>& ctx, std::int32_t i,
                                         std::int32_t j, const Emit& emit) {
  const std::int32_t s0 = b.offsets[c];
  const T scale = ctx.jacobi ? ctx.omega * b.jacobi_scale[s0] : T(1);
  const XpbdTerm<T> term = blockTerm(b, ctx, c);
  const DistanceCorrection<T> r =
      projectDistance(ctx.x[i], ctx.x[j], ctx.w[i], ctx.w[j], b.rest[c], term, b.lambda[c].x);
  emit(s0, i, r.dp0, scale);
  emit(s0 + 1, j, r.dp1, scale);
  b.lambda[c].x += r.dlambda * scale;
}

template <typename T>
INC_HD void projectDistanceConstraint(const BlockView<T>& b, int c, const SolveContext<T>& ctx) {
  const std::int32_t s0 = b.offsets[c];
  projectDistanceConstraintIds(b, c, ctx, b.ids[s0], b.ids[s0 + 1], EmitToBlock<T>{b, ctx});
}

// Bending (kBend) or tet volume (four particles). The kind is a template argument so that a kernel specialised for
// one kind carries only that kind's code (registers, hence occupancy: kernels/pbd_projection_kernels.cu).
// `id`: the constraint's four particle ids (b.ids + offsets[c], or a backend's copy of them).
template <bool kBend, typename T, typename Emit>
INC_HD void projectFourParticleConstraintIds(const BlockView<T>& b, int c, const SolveContext<T>& ctx,
                                             const std::int32_t* id, const Emit& emit) {
  const std::int32_t s0 = b.offsets[c];
  const T scale = ctx.jacobi ? ctx.omega * b.jacobi_scale[s0] : T(1);
  const Vec3<T>* x = ctx.x;
  const T* w = ctx.w;
  const XpbdTerm<T> term = blockTerm(b, ctx, c);
  Vec3<T> dp[4];
  T dl;
  if (kBend) {
    const BendingCorrection<T> r = projectBending(x[id[0]], x[id[1]], x[id[2]], x[id[3]], w[id[0]], w[id[1]], w[id[2]],
                                                  w[id[3]], b.rest[c], term, b.lambda[c].x);
    for (int k = 0; k < 4; ++k) dp[k] = r.dp[k];
    dl = r.dlambda;
  } else {
    const TetVolumeCorrection<T> r = projectTetVolume(x[id[0]], x[id[1]], x[id[2]], x[id[3]], w[id[0]], w[id[1]],
                                                      w[id[2]], w[id[3]], b.rest[c], term, b.lambda[c].x);
    for (int k = 0; k < 4; ++k) dp[k] = r.dp[k];
    dl = r.dlambda;
  }
  for (int k = 0; k < 4; ++k) emit(s0 + k, id[k], dp[k], scale);
  b.lambda[c].x += dl * scale;
}

template <bool kBend, typename T>
INC_HD void projectFourParticleConstraintOf(const BlockView<T>& b, int c, const SolveContext<T>& ctx) {
  projectFourParticleConstraintIds<kBend>(b, c, ctx, b.ids + b.offsets[c], EmitToBlock<T>{b, ctx});
}

template <typename T>
INC_HD void projectFourParticleConstraint(const BlockView<T>& b, int c, const SolveContext<T>& ctx) {
  if (b.kind == kBending)
    projectFourParticleConstraintOf<true>(b, c, ctx);
  else
    projectFourParticleConstraintOf<false>(b, c, ctx);
}

template <typename T>
INC_HD void projectLaplacianConstraint(const BlockView<T>& b, int c, const SolveContext<T>& ctx) {
  const std::int32_t s0 = b.offsets[c], s1 = b.offsets[c + 1];
  const T scale = ctx.jacobi ? ctx.omega * b.jacobi_scale[s0] : T(1);
  const Vec3<T> rest = laplacianRest(b, c, ctx);
  const XpbdTerm<T> term = blockTerm(b, ctx, c);
  const LaplacianCorrection<T> r = projectLaplacian(ctx.x, ctx.w, b.ids + s0, s1 - s0, rest, term, b.lambda[c]);
  emitCorrection(b, ctx, s0, r.d_center, scale);
  for (std::int32_t s = s0 + 1; s < s1; ++s) emitCorrection(b, ctx, s, r.dlambda * (-ctx.w[b.ids[s]] * r.inv_n), scale);
  b.lambda[c] += r.dlambda * scale;
}

// The two member passes of shape-matching cluster c, given its frame and rotation. `goals`, when given (room for
// the cluster's members), keeps each member's goal correction from pass 1 for pass 2 instead of computing it
// twice (the same values: a member's goal depends only on its own position, which pass 1 does not move, and the
// cluster frame).
template <typename T>
INC_HD void shapeMatchMembers(const BlockView<T>& b, int c, const SolveContext<T>& ctx, const Mat3<T>& rot,
                              const Vec3<T>& x_cm, GoalCorrection<T>* goals) {
  const std::int32_t s0 = b.offsets[c], s1 = b.offsets[c + 1];
  // Pass 1: the cluster's net momentum change (see shapeMatchMomentum), removed in pass 2 by a shift.
  Vec3<T> dmom;
  T mov_mass = T(0);
  if (goals) {
    for (std::int32_t s = s0; s < s1; ++s) {
      goals[s - s0] = shapeMatchGoal(b, ctx, s, rot, x_cm);
      shapeMatchMomentumTerm(b, ctx, s, goals[s - s0], dmom, mov_mass);
    }
  } else {
    for (std::int32_t s = s0; s < s1; ++s) shapeMatchMomentum(b, ctx, s, rot, x_cm, dmom, mov_mass);
  }
  const Vec3<T> shift = shapeMatchShift(dmom, mov_mass);
  // Pass 2: goals from the cluster frame computed above; a member's goal does not depend on its own
  // update, so Gauss-Seidel may write each member in place.
  if (goals) {
    for (std::int32_t s = s0; s < s1; ++s) shapeMatchApplyTerm(b, ctx, s, goals[s - s0], shift);
  } else {
    for (std::int32_t s = s0; s < s1; ++s) shapeMatchApply(b, ctx, s, rot, x_cm, shift);
  }
}

// One shape-matching cluster: frame, rotation, then the two member passes (shapeMatchMembers).
template <typename T>
INC_HD void projectShapeMatchingCluster(const BlockView<T>& b, int c, const SolveContext<T>& ctx,
                                        GoalCorrection<T>* goals = nullptr) {
  const std::int32_t s0 = b.offsets[c], s1 = b.offsets[c + 1];
  const std::int32_t centre = b.ids[s0];
  const ClusterFrame<T> f = clusterFrame(ctx.x, ctx.mass, b.ids + s0, b.rest_vec + s0, s1 - s0);
  const Mat3<T> rot = shapeMatchRotation(ctx, centre, f.a_pq);
  shapeMatchMembers(b, c, ctx, rot, f.x_cm, goals);
}

// Shape-matching clusters cs[0..count) (count <= kMaxRotationBatch) projected as projectShapeMatchingCluster
// projects each in turn, with the same result, when they are independent: no cluster moves a particle that
// another one's frame reads (a Jacobi block, or one Gauss-Seidel colour) and no two share a centre. Their rotation
// extractions run interleaved (extractRotations), which a CPU core overlaps.
template <typename T>
INC_HD void projectShapeMatchingClusters(const BlockView<T>& b, const std::int32_t* cs, int count,
                                         const SolveContext<T>& ctx, GoalCorrection<T>* goals = nullptr) {
  ClusterFrame<T> f[kMaxRotationBatch];
  Mat3<T> a[kMaxRotationBatch];
  Quat<T> q[kMaxRotationBatch];
  for (int k = 0; k < count; ++k) {
    const std::int32_t s0 = b.offsets[cs[k]], s1 = b.offsets[cs[k] + 1];
    f[k] = clusterFrame(ctx.x, ctx.mass, b.ids + s0, b.rest_vec + s0, s1 - s0);
    a[k] = f[k].a_pq;
    q[k] = ctx.rotation[b.ids[s0]];
  }
  extractRotations(a, q, count, ctx.rotation_iterations);
  for (int k = 0; k < count; ++k) {
    ctx.rotation[b.ids[b.offsets[cs[k]]]] = q[k];
    shapeMatchMembers(b, cs[k], ctx, quatToMatrix(q[k]), f[k].x_cm, goals);
  }
}

// Projects constraint c once (any kind).
template <typename T>
INC_HD void projectConstraint(const BlockView<T>& b, int c, const SolveContext<T>& ctx) {
  switch (b.kind) {
    case kDistance: projectDistanceConstraint(b, c, ctx); break;
    case kBending:
    case kTetVolume: projectFourParticleConstraint(b, c, ctx); break;
    case kLaplacian: projectLaplacianConstraint(b, c, ctx); break;
    case kShapeMatching: projectShapeMatchingCluster(b, c, ctx); break;
    default: break;
  }
}

// Rotation of one cluster without applying its goals (for skinning when shape matching is not solved).
template <typename T>
INC_HD void updateClusterRotation(const BlockView<T>& b, int c, const SolveContext<T>& ctx) {
  const std::int32_t s0 = b.offsets[c], s1 = b.offsets[c + 1];
  const ClusterFrame<T> f = clusterFrame(ctx.x, ctx.mass, b.ids + s0, b.rest_vec + s0, s1 - s0);
  ctx.rotation[b.ids[s0]] = extractRotation(f.a_pq, ctx.rotation[b.ids[s0]], ctx.rotation_iterations);
}

// Grasp attachment of one particle to a moving target point: the zero-rest-length compliant constraint
// C = x - target (3-vector) with compliance alpha (m/N); alpha = 0 holds the particle rigidly in the jaws.
// Each attached particle has one attachment, so all of them are projected in parallel without conflict.
template <typename T>
INC_HD void projectAttachment(Vec3<T>& x, T w, const Vec3<T>& target, T compliance, bool xpbd, T dt, Vec3<T>& lambda) {
  const XpbdTerm<T> term = xpbdTerm(xpbd, compliance, T(1), dt);
  const GoalCorrection<T> r = projectGoal(x, w, target, term, lambda);
  x += r.dp;
  lambda += r.dlambda;
}

// Jacobi gather: the sum of the (already scaled) corrections of particle p's slots, in ascending slot order.
template <typename T>
INC_HD Vec3<T> gatherCorrection(const BlockView<T>& b, std::int32_t p) {
  Vec3<T> sum;
  for (std::int32_t k = b.particle_offsets[p]; k < b.particle_offsets[p + 1]; ++k)
    sum += b.slot_corr[b.particle_slots[k]];
  return sum;
}

// XPBD residual |C + alpha~ lambda| of distance constraint c (m): zero when the substep's solve converged.
template <typename T>
INC_HD T distanceResidual(const BlockView<T>& b, int c, const Vec3<T>* x, bool xpbd, T dt) {
  const std::int32_t i = b.ids[b.offsets[c]], j = b.ids[b.offsets[c] + 1];
  const T cval = norm(x[i] - x[j]) - b.rest[c];
  const T at = xpbd ? b.compliance[c] / (dt * dt) : T(0);
  return std::fabs(cval + at * b.lambda[c].x);
}

// ---------------------------------------------------------------------------------------------
// Per-particle substep steps.

// Symplectic Euler prediction with mass-proportional damping: v <- v exp(-damping dt) + dt g; x <- x + dt v.
template <typename T>
INC_HD void predictParticle(Vec3<T>& x, Vec3<T>& v, Vec3<T>& x_prev, T w, const Vec3<T>& g, T damping_factor, T dt) {
  x_prev = x;
  if (w > T(0)) {
    v = v * damping_factor + g * dt;
    x += v * dt;
  }
}

template <typename T>
INC_HD Vec3<T> lerp(const Vec3<T>& a, const Vec3<T>& b, T t) {
  return a + (b - a) * t;
}

template <typename T>
INC_HD CapsuleCollider<T> lerpCapsule(const CapsuleCollider<T>& a, const CapsuleCollider<T>& b, T t) {
  CapsuleCollider<T> c;
  c.a = lerp(a.a, b.a, t);
  c.b = lerp(a.b, b.b, t);
  c.radius = a.radius + (b.radius - a.radius) * t;
  c.friction = a.friction;
  return c;
}

// All contacts of one sphere, resolved one after another (Gauss-Seidel over its own contacts). Tools are
// interpolated to the substep's end time t in [0, 1] of the frame (t0: its start). The static colliders (planes,
// boxes) meet the sphere at r - inset (at least 0): the organ's surface, not the ball, rests on them
// (PbdModel::contact_inset); tools meet the whole ball. With `x_prev` (the sphere's substep start) each push is
// followed by its collider's Coulomb friction (coulombAfterContact; toolCoulombAfterContact relative to a tool).
template <typename T>
INC_HD Vec3<T> resolveContacts(Vec3<T> x, T r, T inset, const Vec3<T>* x_prev, const PlaneCollider<T>* planes, int np,
                               const BoxCollider<T>* boxes, int nb, const CapsuleCollider<T>* tools_from,
                               const CapsuleCollider<T>* tools_to, int nt, T t0, T t) {
  const T rs = r > inset ? r - inset : T(0);
  for (int k = 0; k < np; ++k) {
    const Vec3<T> c = planeContact(x, rs, planes[k]);
    x += c;
    if (x_prev) x = coulombAfterContact(x, c, *x_prev, planes[k].friction);
  }
  for (int k = 0; k < nb; ++k) {
    const Vec3<T> c = boxContact(x, rs, boxes[k]);
    x += c;
    if (x_prev) x = coulombAfterContact(x, c, *x_prev, boxes[k].friction);
  }
  for (int k = 0; k < nt; ++k) {
    const CapsuleCollider<T> tool = lerpCapsule(tools_from[k], tools_to[k], t);
    const Vec3<T> c = capsuleContact(x, r, tool);
    x += c;
    if (x_prev && tool.friction > T(0))
      x = toolCoulombAfterContact(x, c, *x_prev, lerpCapsule(tools_from[k], tools_to[k], t0), tool);
  }
  return x;
}

}  // namespace inc::pbd
