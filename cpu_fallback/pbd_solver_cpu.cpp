// CPU PBD/XPBD frame: predict, per-block Jacobi (slot output + per-particle gather) or coloured Gauss-Seidel, contacts,
// velocities, radii.
#include "cpu_fallback/pbd_solver_cpu.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "base/parallel.h"
#include "base/team.h"
#include "cpu_fallback/pbd_rotation_lanes.h"
#include "physics/pbd_block.h"
#include "physics/pbd_terms3.h"
#include "physics/pbd_volume.h"

namespace inc::cpu {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// A frame runs on a team of threads kept for the whole frame (cpu/team.h: one parallel region, a barrier
// between dependent phases) when its blocks hold at least this many constraint slots; smaller models run on
// the calling thread (a barrier costs about as much as projecting a few dozen slots).
constexpr std::int64_t kTeamMinSlots = 4096;
// and one thread per this many slots at most: each thread of a team adds to every barrier's cost (about 240
// barriers a frame for Jacobi), so a liver-sized model (~20k slots) takes 5 threads, not every core of a
// workstation.
constexpr std::int64_t kTeamSlotsPerThread = 4096;

// Work of one constraint for the static split of a phase over the team: its slots, plus for a shape-matching
// cluster the polar decomposition, which costs about as much as six members.
std::int64_t constraintWeight(PbdConstraintKind kind, std::int32_t slots) {
  return std::int64_t(slots) + (kind == PbdConstraintKind::ShapeMatching ? 6 : 0);
}

// Cuts items [0, m) with weight prefix sums `prefix` (size m + 1) into `parts` contiguous ranges of about equal
// weight: range t is [out[t], out[t + 1]).
void balancedSplit(const std::vector<std::int64_t>& prefix, int parts, std::int32_t* out) {
  const std::int64_t total = prefix.back();
  const std::int32_t m = std::int32_t(prefix.size() - 1);
  out[0] = 0;
  for (int t = 1; t < parts; ++t) {
    const std::int64_t target = total * t / parts;
    out[t] = std::int32_t(std::lower_bound(prefix.begin(), prefix.end(), target) - prefix.begin());
    out[t] = std::max(out[t - 1], std::min(out[t], m));
  }
  out[parts] = m;
}

// Shape-matching clusters projected together (at most pbd::kMaxRotationBatch): enough independent rotation
// extractions to keep a core busy through their dependent chains, and one per lane of extractRotationsLanes.
constexpr int kClusterBatch = 4;
static_assert(kClusterBatch <= kRotationLaneBatch && kClusterBatch <= pbd::kMaxRotationBatch, "batch size");

// Set by tests: every constraint projected by pbd::projectConstraint, one at a time (the shared scalar code the GPU
// runs), instead of projectRange's per-kind loops and vector forms; the results must be the same bits.
std::atomic<bool> g_reference_loop{false};

#if defined(__GNUC__)
#define INC_FLATTEN __attribute__((flatten))
#else
#define INC_FLATTEN
#endif

// The XPBD term of a block's multiplier i (pbd::blockTerm's value): from the per-frame table where there is one (the
// usual case on the CPU), else blockTerm itself. Chosen once per loop instead of once per constraint or member.
template <typename T>
struct AlphaTableTerm {
  const T* alpha_tilde;
  pbd::XpbdTerm<T> operator()(std::int32_t i) const {
    pbd::XpbdTerm<T> t;  // stiffness 1, as blockTerm returns it from the table
    t.alpha_tilde = alpha_tilde[i];
    return t;
  }
};
template <typename T>
struct BlockTermOf {
  const pbd::BlockView<T>& b;
  const pbd::SolveContext<T>& ctx;
  pbd::XpbdTerm<T> operator()(std::int32_t i) const { return pbd::blockTerm(b, ctx, i); }
};

// Calls f(kJacobi, term) with the solver as a compile-time constant (std::true_type: Jacobi) and the block's term
// source, so that a loop body instantiated for each has neither branch inside (the compiler kept both inside the
// loops, and reloaded the views' array addresses at every step: the stores could alias the views).
template <typename T, class F>
void withSolverAndTerm(const pbd::BlockView<T>& b, const pbd::SolveContext<T>& ctx, F&& f) {
  if (ctx.xpbd && b.alpha_tilde) {
    if (ctx.jacobi)
      f(std::true_type{}, AlphaTableTerm<T>{b.alpha_tilde});
    else
      f(std::false_type{}, AlphaTableTerm<T>{b.alpha_tilde});
  } else {
    if (ctx.jacobi)
      f(std::true_type{}, BlockTermOf<T>{b, ctx});
    else
      f(std::false_type{}, BlockTermOf<T>{b, ctx});
  }
}

// pbd::projectDistanceConstraint of constraints order[q] (or q) for q in [q0, q1), two per step, inlined: a
// constraint is a short chain of a square root and two divisions, and two independent chains side by side keep the
// core busy. The solver and the term source fixed (withSolverAndTerm); the same operations in the same order.
template <typename T>
INC_FLATTEN void projectDistanceRange(const pbd::BlockView<T>& v, const std::int32_t* order, std::int32_t q0,
                                      std::int32_t q1, const pbd::SolveContext<T>& ctx) {
  withSolverAndTerm(v, ctx, [&](auto jacobi, auto term) {
    constexpr bool kJacobi = decltype(jacobi)::value;
    const std::int32_t* offsets = v.offsets;
    const std::int32_t* ids = v.ids;
    const T* rest = v.rest;
    const T* jscale = v.jacobi_scale;
    Vec3<T>* lambda = v.lambda;
    Vec3<T>* slot_corr = v.slot_corr;
    Vec3<T>* x = ctx.x;
    const T* w = ctx.w;
    const T omega = ctx.omega;
    const auto project = [&](std::int32_t c) {
      const std::int32_t s0 = offsets[c];
      const T scale = kJacobi ? omega * jscale[s0] : T(1);
      const std::int32_t i = ids[s0], j = ids[s0 + 1];
      const pbd::DistanceCorrection<T> r = pbd::projectDistance(x[i], x[j], w[i], w[j], rest[c], term(c), lambda[c].x);
      if (kJacobi) {  // pbd::emitCorrection
        slot_corr[s0] = r.dp0 * scale;
        slot_corr[s0 + 1] = r.dp1 * scale;
      } else {  // fixed particles are never written (pbd::emitCorrection)
        if (w[i] > T(0)) x[i] += r.dp0;
        if (w[j] > T(0)) x[j] += r.dp1;
      }
      lambda[c].x += r.dlambda * scale;
    };
    std::int32_t q = q0;
    for (; q + 1 < q1; q += 2) {
      project(order ? order[q] : q);
      project(order ? order[q + 1] : q + 1);
    }
    if (q < q1) project(order ? order[q] : q);
  });
}

// pbd::clusterFrame of clusters cs[0..count), one after another.
template <typename T>
void clusterFramesBatch(const pbd::BlockView<T>& b, const std::int32_t* cs, int count, const pbd::SolveContext<T>& ctx,
                        pbd::ClusterFrame<T>* f) {
  for (int k = 0; k < count; ++k) {
    const std::int32_t s0 = b.offsets[cs[k]], s1 = b.offsets[cs[k] + 1];
    f[k] = pbd::clusterFrame(ctx.x, ctx.mass, b.ids + s0, b.rest_vec + s0, s1 - s0);
  }
}

// pbd::shapeMatchMembers with each member's goal correction kept from pass 1 for pass 2 in `goals`.
template <typename T>
void shapeMatchMembersKept(const pbd::BlockView<T>& b, int c, const pbd::SolveContext<T>& ctx, const Mat3<T>& rot,
                           const Vec3<T>& x_cm, pbd::GoalCorrection<T>* goals) {
  pbd::shapeMatchMembers(b, c, ctx, rot, x_cm, goals);
}

#if defined(__GNUC__)
// float32: a member's x, y and z in three lanes of a 16-byte vector (SSE2 on x86-64, which every x86-64 CPU has;
// other targets get the compiler's own lowering), so each sum of clusterFrame is one vector operation instead of
// three (nine for a row of the moment matrix: three). The terms are those of physics/pbd_cluster_batch.h
// (clusterFrame's operations in its order), lane by lane, so every frame equals clusterFrame's bit for bit.
typedef float F4 __attribute__((vector_size(16)));
constexpr std::int32_t kMaxKeptMembers = 64;  // members of a cluster whose pass-1 results stay on the stack

inline F4 loadVec3(const Vec3<float>& v) {
#if defined(__SSE2__)
  // x, y in one 8-byte load, z in a 4-byte one (the 16-byte load past z could leave the array).
  // The 8 bytes of x, y go through memcpy: a float pair is only 4-byte aligned, and dereferencing it as a double
  // (what _mm_load_sd does) is undefined behaviour; the compiler emits the same single unaligned movsd.
  double xy;
  std::memcpy(&xy, &v.x, sizeof xy);
  return F4(_mm_movelh_ps(_mm_castpd_ps(_mm_set_sd(xy)), _mm_load_ss(&v.z)));
#else
  return F4{v.x, v.y, v.z, 0.0f};
#endif
}

inline void storeVec3(Vec3<float>& out, const F4& v) { out = Vec3<float>(v[0], v[1], v[2]); }

template <>
void clusterFramesBatch<float>(const pbd::BlockView<float>& b, const std::int32_t* cs, int count,
                               const pbd::SolveContext<float>& ctx, pbd::ClusterFrame<float>* f) {
  static_assert(sizeof(Vec3<float>) == 12, "Vec3<float> is x, y, z");
  const Vec3<float>* x = ctx.x;
  const float* mass = ctx.mass;
  for (int k = 0; k < count; ++k) {
    const std::int32_t s0 = b.offsets[cs[k]], s1 = b.offsets[cs[k] + 1];
    F4 c = {};
    float msum = 0.0f;
    for (std::int32_t s = s0; s < s1; ++s) {
      const std::int32_t i = b.ids[s];
      pbd::clusterCentreTerm3(c, msum, loadVec3(x[i]), mass[i]);
    }
    if (msum > 0.0f) c = c * (1.0f / msum);  // clusterFrame: x_cm *= 1 / sum m_k
    F4 a[3] = {};
    for (std::int32_t s = s0; s < s1; ++s) {
      const std::int32_t i = b.ids[s];
      pbd::clusterMomentTerm3(a, loadVec3(x[i]) - c, loadVec3(b.rest_vec[s]), mass[i]);
    }
    f[k].x_cm = Vec3<float>(c[0], c[1], c[2]);
    for (int r = 0; r < 3; ++r)
      for (int j = 0; j < 3; ++j) f[k].a_pq.m[r][j] = a[r][j];
  }
}

// The member passes of shapeMatchMembersKept<float> for one solver (kJacobi: slot output and Jacobi scales) and one
// source of XPBD terms (withSolverAndTerm), the arrays' addresses in locals; the same operations per member in the
// same order.
template <bool kJacobi, class Term>
void shapeMatchMembersVec(const pbd::BlockView<float>& b, int c, const pbd::SolveContext<float>& ctx, const F4& c0,
                          const F4& c1, const F4& c2, const F4& cm, Term term) {
  const std::int32_t s0 = b.offsets[c], s1 = b.offsets[c + 1];
  const std::int32_t* ids = b.ids;
  const Vec3<float>* rest = b.rest_vec;
  Vec3<float>* lambda = b.lambda;
  const float* jscale = b.jacobi_scale;
  Vec3<float>* slot_corr = b.slot_corr;
  Vec3<float>* x = ctx.x;
  const float* w = ctx.w;
  const float* mass = ctx.mass;
  const float omega = ctx.omega;
  // pbd::slotScale
  const auto slotScale = [&](std::int32_t s) { return kJacobi ? omega * jscale[s] : 1.0f; };
  // Pass 1: goals and the momentum change, each member's (dp, dlambda) kept in registers' form for pass 2.
  F4 kept_dp[kMaxKeptMembers], kept_dl[kMaxKeptMembers];
  F4 dmom = {};
  float mov_mass = 0.0f;
  for (std::int32_t s = s0; s < s1; ++s) {
    const std::int32_t p = ids[s];
    const float wp = w[p];
    const F4 goal = pbd::mulColumns(c0, c1, c2, loadVec3(rest[s])) + cm;
    F4 dp;
    kept_dl[s - s0] = pbd::projectGoal3(loadVec3(x[p]), wp, goal, term(s), loadVec3(lambda[s]), dp);
    kept_dp[s - s0] = dp;
    pbd::shapeMatchMomentumTerm3(dmom, mov_mass, dp, slotScale(s), wp, mass[p]);
  }
  const Vec3<float> shift3 = pbd::shapeMatchShift(Vec3<float>(dmom[0], dmom[1], dmom[2]), mov_mass);
  const F4 shift = loadVec3(shift3);
  // Pass 2: corrections (slot output for Jacobi, in place for Gauss-Seidel) and multipliers.
  for (std::int32_t s = s0; s < s1; ++s) {
    const std::int32_t p = ids[s];
    const float sc = slotScale(s);
    const F4 d = pbd::shapeMatchApplyCorrection3(kept_dp[s - s0], sc, w[p], shift);
    if (kJacobi)
      storeVec3(slot_corr[s], d);
    else if (w[p] > 0.0f)
      storeVec3(x[p], loadVec3(x[p]) + d);  // ctx.x[p] += d (fixed members never written)
    storeVec3(lambda[s], loadVec3(lambda[s]) + kept_dl[s - s0] * sc);
  }
}

// The goal of a member (rot r_k + x_cm) and its correction in vector lanes likewise: one division for the three
// multipliers instead of three (physics/pbd_terms3.h: Mat3 * Vec3's and projectGoal's operations).
template <>
void shapeMatchMembersKept<float>(const pbd::BlockView<float>& b, int c, const pbd::SolveContext<float>& ctx,
                                  const Mat3<float>& rot, const Vec3<float>& x_cm, pbd::GoalCorrection<float>* goals) {
  if (b.offsets[c + 1] - b.offsets[c] > kMaxKeptMembers) {  // (no such cluster in the scenes: ~15-30 members)
    pbd::shapeMatchMembers(b, c, ctx, rot, x_cm, goals);
    return;
  }
  const F4 c0 = {rot.m[0][0], rot.m[1][0], rot.m[2][0], 0.0f};
  const F4 c1 = {rot.m[0][1], rot.m[1][1], rot.m[2][1], 0.0f};
  const F4 c2 = {rot.m[0][2], rot.m[1][2], rot.m[2][2], 0.0f};
  const F4 cm = loadVec3(x_cm);
  withSolverAndTerm(b, ctx, [&](auto jacobi, auto term) {
    shapeMatchMembersVec<decltype(jacobi)::value>(b, c, ctx, c0, c1, c2, cm, term);
  });
}
#endif

// pbd::projectLaplacianConstraint.
template <typename T>
void projectLaplacianCpu(const pbd::BlockView<T>& b, int c, const pbd::SolveContext<T>& ctx) {
  pbd::projectLaplacianConstraint(b, c, ctx);
}

#if defined(__GNUC__)
// float32: the neighbours' sum, the three multipliers and the corrections as vectors (physics/pbd_terms3.h:
// projectLaplacian's and laplacianFromSums' operations in their order; the same values).
template <>
void projectLaplacianCpu<float>(const pbd::BlockView<float>& b, int c, const pbd::SolveContext<float>& ctx) {
  const std::int32_t s0 = b.offsets[c], s1 = b.offsets[c + 1];
  const int count = int(s1 - s0);
  if (count < 2) {
    pbd::projectLaplacianConstraint(b, c, ctx);
    return;
  }
  const float scale = ctx.jacobi ? ctx.omega * b.jacobi_scale[s0] : 1.0f;
  const Vec3<float> rest = pbd::laplacianRest(b, c, ctx);
  const pbd::XpbdTerm<float> term = pbd::blockTerm(b, ctx, c);
  const std::int32_t* ids = b.ids + s0;
  F4 mean_sum = {};
  float wn = 0.0f;
  for (int k = 1; k < count; ++k) {
    mean_sum = mean_sum + loadVec3(ctx.x[ids[k]]);
    wn += ctx.w[ids[k]];
  }
  float inv_n;
  F4 d_center;
  const F4 dl = pbd::laplacianFromSums3(loadVec3(ctx.x[ids[0]]), ctx.w[ids[0]], mean_sum, wn, count, loadVec3(rest),
                                        term, loadVec3(b.lambda[c]), inv_n, d_center);
  if (ctx.jacobi) {
    storeVec3(b.slot_corr[s0], d_center * scale);
    for (std::int32_t s = s0 + 1; s < s1; ++s) storeVec3(b.slot_corr[s], dl * (-ctx.w[b.ids[s]] * inv_n) * scale);
  } else {
    // pbd::emitCorrection: fixed particles are never written
    if (ctx.w[ids[0]] > 0.0f) storeVec3(ctx.x[ids[0]], loadVec3(ctx.x[ids[0]]) + d_center);
    for (std::int32_t s = s0 + 1; s < s1; ++s) {
      Vec3<float>& xs = ctx.x[b.ids[s]];
      if (ctx.w[b.ids[s]] > 0.0f) storeVec3(xs, loadVec3(xs) + dl * (-ctx.w[b.ids[s]] * inv_n));
    }
  }
  storeVec3(b.lambda[c], loadVec3(b.lambda[c]) + dl * scale);
}
#endif

// pbd::projectShapeMatchingClusters (frames, interleaved rotation extractions, member passes) with the frames of
// clusterFramesBatch and the member passes of shapeMatchMembersKept: the same values. Used where there are no
// SIMD lanes for projectShapeMatchingPipelined below.
template <typename T>
void projectShapeMatchingClustersKept(const pbd::BlockView<T>& b, const std::int32_t* cs, int count,
                                      const pbd::SolveContext<T>& ctx, pbd::GoalCorrection<T>* goals) {
  pbd::ClusterFrame<T> f[pbd::kMaxRotationBatch];
  Mat3<T> a[pbd::kMaxRotationBatch];
  pbd::Quat<T> q[pbd::kMaxRotationBatch];
  clusterFramesBatch(b, cs, count, ctx, f);
  for (int k = 0; k < count; ++k) {
    a[k] = f[k].a_pq;
    q[k] = ctx.rotation[b.ids[b.offsets[cs[k]]]];
  }
  pbd::extractRotations(a, q, count, ctx.rotation_iterations);
  for (int k = 0; k < count; ++k) {
    ctx.rotation[b.ids[b.offsets[cs[k]]]] = q[k];
    shapeMatchMembersKept(b, cs[k], ctx, pbd::quatToMatrix(q[k]), f[k].x_cm, goals);
  }
}

// The next batch of shape-matching clusters order[q] (or q) from [q, q1) into cs: up to kClusterBatch, ending early
// where a cluster's centre would repeat (the second would have to start from the rotation the first writes).
// Advances q past the batch; returns its size.
template <typename T>
int nextClusterBatch(const pbd::BlockView<T>& v, const std::int32_t* order, std::int32_t& q, std::int32_t q1,
                     std::int32_t* cs) {
  int k = 0;
  for (; k < kClusterBatch && q < q1; ++k, ++q) {
    cs[k] = order ? order[q] : q;
    bool repeat = false;
    for (int j = 0; j < k; ++j) repeat = repeat || v.ids[v.offsets[cs[j]]] == v.ids[v.offsets[cs[k]]];
    if (repeat) break;
  }
  return k;
}

#if defined(INC_HAVE_ROTATION_LANES)
// The shape-matching clusters of [q0, q1) as the batches of projectShapeMatchingClustersKept, software-pipelined:
// batch i+1's rotation extraction (in SIMD lanes: cpu_fallback/pbd_rotation_lanes.h) is a chain of dependent steps
// that alone leaves the core mostly idle (it took ~17 % of the frame's time for ~8 % of its instructions), while
// batch i's member passes are independent, throughput-bound work. So batch i+1's frames are computed and its steps
// issued one at a time between batch i's clusters' member passes, and the core runs both. Every value is the one
// the batch-by-batch loop computes: the clusters of a phase (a Jacobi block, or one Gauss-Seidel colour) are
// independent (batch i's member passes move no particle that batch i+1's frames read), and batch i's rotations are
// written before batch i+1 reads its warm starts.
template <typename T>
void projectShapeMatchingPipelined(const pbd::BlockView<T>& v, const std::int32_t* order, std::int32_t q0,
                                   std::int32_t q1, const pbd::SolveContext<T>& ctx, pbd::GoalCorrection<T>* goals) {
  struct Batch {
    std::int32_t cs[pbd::kMaxRotationBatch] = {};
    int count = 0;
    pbd::ClusterFrame<T> f[kClusterBatch];
    pbd::Quat<T> q[kClusterBatch];
  };
  RotationLanes<typename RotationLanesOf<T>::type> rot;
  // Frames and rotation warm starts of the next batch, and its extraction started (no step taken).
  const auto startBatch = [&](Batch& b, std::int32_t& q) {
    b.count = nextClusterBatch(v, order, q, q1, b.cs);
    if (b.count == 0) return;
    clusterFramesBatch(v, b.cs, b.count, ctx, b.f);
    Mat3<T> a[kClusterBatch];
    for (int k = 0; k < b.count; ++k) {
      a[k] = b.f[k].a_pq;
      b.q[k] = ctx.rotation[v.ids[v.offsets[b.cs[k]]]];
    }
    rot.start(a, b.q, b.count);
  };
  const auto finishBatch = [&](Batch& b) {
    rot.finish(b.q, b.count);
    for (int k = 0; k < b.count; ++k) ctx.rotation[v.ids[v.offsets[b.cs[k]]]] = b.q[k];
  };
  const int iterations = ctx.rotation_iterations;
  Batch batches[2];
  std::int32_t q = q0;
  startBatch(batches[0], q);
  if (batches[0].count == 0) return;
  for (int it = 0; it < iterations; ++it)
    if (!rot.step()) break;
  finishBatch(batches[0]);
  for (int i = 0;; i ^= 1) {
    Batch& cur = batches[i];
    Batch& next = batches[i ^ 1];
    startBatch(next, q);
    bool stepping = next.count > 0 && iterations > 0;
    int it = 0;
    for (int k = 0; k < cur.count; ++k) {
      if (stepping) stepping = rot.step() && ++it < iterations;
      shapeMatchMembersKept(v, cur.cs[k], ctx, pbd::quatToMatrix(cur.q[k]), cur.f[k].x_cm, goals);
    }
    while (stepping) stepping = rot.step() && ++it < iterations;
    if (next.count == 0) break;
    finishBatch(next);
  }
}
#endif

// Projects constraints order[q] (or q when order is null) for q in [q0, q1) of one block: the kind's function
// from physics/pbd_block.h called directly (the same one projectConstraint dispatches to), so the loop has no
// per-constraint dispatch. `goals`: room for one cluster's members (shape matching keeps pass 1's goals for
// pass 2), or null.
template <typename T>
void projectRange(const pbd::BlockView<T> v, const std::int32_t* order, std::int32_t q0, std::int32_t q1,
                  const pbd::SolveContext<T> ctx, pbd::GoalCorrection<T>* goals) {
  if (g_reference_loop.load(std::memory_order_relaxed)) {
    for (std::int32_t q = q0; q < q1; ++q) pbd::projectConstraint(v, order ? order[q] : q, ctx);
    return;
  }
  switch (v.kind) {
    case pbd::kDistance: projectDistanceRange(v, order, q0, q1, ctx); break;
    case pbd::kLaplacian:
      for (std::int32_t q = q0; q < q1; ++q) projectLaplacianCpu(v, order ? order[q] : q, ctx);
      break;
    case pbd::kShapeMatching:
#if defined(INC_HAVE_ROTATION_LANES)
      if (goals) {
        projectShapeMatchingPipelined(v, order, q0, q1, ctx, goals);
        break;
      }
#endif
      // In batches of independent clusters (the phase's clusters are; a batch ends early only where a centre
      // would repeat), whose rotation extractions the core then overlaps.
      for (std::int32_t q = q0; q < q1;) {
        std::int32_t cs[pbd::kMaxRotationBatch];
        const int k = nextClusterBatch(v, order, q, q1, cs);
        if (goals)
          projectShapeMatchingClustersKept(v, cs, k, ctx, goals);
        else
          pbd::projectShapeMatchingClusters(v, cs, k, ctx);
      }
      break;
    default:
      for (std::int32_t q = q0; q < q1; ++q) pbd::projectConstraint(v, order ? order[q] : q, ctx);
      break;
  }
}

template <typename T>
class PbdCpuBackend final : public PbdBackend<T> {
 public:
  BackendKind kind() const override { return BackendKind::Cpu; }

  void setModel(const PbdModel<T>& model) override {
    model_ = model;
    has_coloring_ = pbdModelHasColoring(model_);
    const std::size_t n = model_.size();
    state_.positions = model_.rest_positions;
    state_.velocities.assign(n, Vec3<T>());
    state_.radii = model_.rest_radii;
    state_.rotations.assign(n, pbd::Quat<T>{});
    x_prev_.assign(n, Vec3<T>());
    w_.assign(n, T(0));
    radii_next_.assign(n, T(0));
    active_.assign(n, 0);
    kinematic_of_.assign(n, -1);
    lambda_.resize(model_.blocks.size());
    slot_corr_.resize(model_.blocks.size());
    alpha_tilde_.assign(model_.blocks.size(), {});
    std::int64_t slots = 0;
    std::size_t residuals = 0;
    max_cluster_ = 0;
    goals_distinct_ = true;
    std::vector<std::uint8_t> seen(n, 0);
    for (std::size_t b = 0; b < model_.blocks.size(); ++b) {
      const auto& bl = model_.blocks[b];
      lambda_[b].assign(bl.multiplierCount(), Vec3<T>());
      slot_corr_[b].assign(bl.slotCount(), Vec3<T>());
      if (!bl.solve) continue;
      slots += std::int64_t(bl.slotCount());
      if (bl.kind == PbdConstraintKind::Distance) residuals += bl.count();
      if (bl.kind == PbdConstraintKind::ShapeMatching)
        for (std::size_t c = 0; c < bl.count(); ++c) {
          const std::int32_t s0 = bl.offsets[c], s1 = bl.offsets[c + 1];
          max_cluster_ = std::max(max_cluster_, std::size_t(s1 - s0));
          // Gauss-Seidel may keep a member's goal between the passes only if no particle is in a cluster twice.
          for (std::int32_t s = s0; s < s1; ++s) goals_distinct_ = goals_distinct_ && !seen[bl.ids[s]]++;
          for (std::int32_t s = s0; s < s1; ++s) seen[bl.ids[s]] = 0;
        }
    }
    residual_.assign(residuals, 0.0);
    solved_slots_ = slots;
    planTeam(teamThreads());
  }

  void setState(const PbdState<T>& s) override {
    const std::size_t n = model_.size();
    if (s.positions.size() != n || s.velocities.size() != n || s.radii.size() != n || s.rotations.size() != n)
      throw InputError("pbd state", "size", "state arrays must have one entry per particle");
    state_ = s;
  }
  void getState(PbdState<T>& s) const override { s = state_; }
  void getPositions(std::vector<Vec3<T>>& positions) const override { positions = state_.positions; }

  MemoryReport memory() const override {
    MemoryReport m;
    const std::size_t n = model_.size();
    m.host_bytes = n * (4 * sizeof(Vec3<T>) + 4 * sizeof(T) + sizeof(pbd::Quat<T>));
    for (std::size_t b = 0; b < model_.blocks.size(); ++b) {
      const auto& bl = model_.blocks[b];
      m.host_bytes += bl.ids.size() * (2 * sizeof(std::int32_t) + sizeof(T) + 2 * sizeof(Vec3<T>)) +
                      bl.multiplierCount() * (sizeof(Vec3<T>) + sizeof(T)) + bl.count() * sizeof(T);
    }
    return m;
  }

  PbdFrameStats advanceFrame(const PbdStepParams<T>& p, const PbdFrameInput<T>& in) override {
    const std::size_t n = model_.size();
    validateFrameInput(n, p, in);
    PbdFrameStats st;
    FrameTimes tm;
    const T dt = p.frame_dt / T(p.substeps);

    // This frame's inverse masses: kinematic (grasped) particles are prescribed, so they get w = 0.
    w_ = model_.inv_mass;
    for (std::size_t k = 0; k < in.kinematic_ids.size(); ++k) {
      w_[in.kinematic_ids[k]] = T(0);
      kinematic_of_[in.kinematic_ids[k]] = std::int32_t(k);
    }
    if (in.kinematic_from_positions) {
      kinematic_from_.resize(in.kinematic_ids.size());
      for (std::size_t k = 0; k < in.kinematic_ids.size(); ++k)
        kinematic_from_[k] = state_.positions[in.kinematic_ids[k]];
    }
    attach_lambda_.assign(in.attach_ids.size(), Vec3<T>());
    if (p.chebyshev_rho > T(0)) sizeChebyshev(in.attach_ids.size());

    pbd::SolveContext<T> ctx;
    ctx.x = state_.positions.data();
    ctx.w = w_.data();
    ctx.mass = model_.masses.data();
    ctx.rotation = state_.rotations.data();
    ctx.xpbd = p.xpbd;
    ctx.dt = dt;
    ctx.jacobi = p.solver == PbdSolverKind::Jacobi;
    if (!ctx.jacobi && !has_coloring_)
      throw InputError("pbd frame", "solver",
                       "the model was built without a colouring (Jacobi only): use the Jacobi solver");
    ctx.omega = p.jacobi_omega;
    ctx.rotation_iterations = p.rotation_iterations;
    // compliance / dt^2 of every multiplier, once per frame instead of once per projection (the same value).
    for (std::size_t bi = 0; bi < model_.blocks.size(); ++bi) {
      const auto& c = model_.blocks[bi].compliance;
      alpha_tilde_[bi].resize(c.size());
      for (std::size_t i = 0; i < c.size(); ++i) alpha_tilde_[bi][i] = c[i] / (dt * dt);
    }
    if (!ctx.jacobi)
      for (const auto& b : model_.blocks)
        if (b.solve) st.colors += b.coloring.colorCount();
    views_.resize(model_.blocks.size());
    for (std::size_t bi = 0; bi < model_.blocks.size(); ++bi) views_[bi] = blockView(bi);

    const int threads = teamThreads();
    if (threads != split_parts_) planTeam(threads);
    team_.run(threads, [&](const Team& t) { frame(t, p, in, ctx, tm); });
    st.threads = team_.lastThreads();
    st.team_stalled = team_.lastStalled();

    for (std::int32_t id : in.kinematic_ids) kinematic_of_[id] = -1;
    st.iterations = p.substeps * p.iterations;
    summarize(st);
    st.stages = {{"predict", tm.predict},
                 {"constraints", tm.constraints},
                 {"collisions", tm.collisions},
                 {"velocities", tm.velocities},
                 {"volume", tm.volume}};
    return st;
  }

 private:
  struct FrameTimes {
    double predict = 0, constraints = 0, collisions = 0, velocities = 0, volume = 0;
  };

  // The whole frame on one thread of the team. Each phase splits its items statically over the team; a barrier
  // separates phases where one reads what another thread wrote. Per-particle phases (gather, contacts,
  // velocities, prediction) give every thread the same particles, so one may follow another without a
  // barrier (the team's size, hence the split, changes only in a barrier). The lead thread times the stages
  // (its own work plus its waits).
  void frame(const Team& t, const PbdStepParams<T>& p, const PbdFrameInput<T>& in, const pbd::SolveContext<T>& ctx,
             FrameTimes& tm) {
    const bool lead = t.lead();
    const T dt = ctx.dt;
    pbd::GoalCorrection<T>* goals =
        ctx.jacobi || goals_distinct_
            ? goal_scratch_.data() + std::size_t(t.id()) * std::max<std::size_t>(max_cluster_, 1)
            : nullptr;
    Clock::time_point t0;

    T cheb_weight = T(1);  // every thread walks the same weights (pbd::chebyshevIteration)
    for (int s = 0; s < p.substeps; ++s) {
      const T t_start = T(s) / T(p.substeps), t_end = T(s + 1) / T(p.substeps);
      if (lead) t0 = Clock::now();
      predictSubstep(t, p, in, dt, t_end);
      t.barrier();
      if (lead) tm.predict += msSince(t0);

      for (int it = 0; it < p.iterations; ++it) {
        if (lead) t0 = Clock::now();
        const bool particle_phase = projectBlocks(t, ctx, goals);
        projectAttachments(t, p, in, dt, t_end, particle_phase);
        if (lead) {
          tm.constraints += msSince(t0);
          t0 = Clock::now();
        }
        finishIteration(t, p, in, it, t_start, t_end, cheb_weight);
        // The next iteration's projections read every particle.
        if (it + 1 < p.iterations) t.barrier();
        if (lead) tm.collisions += msSince(t0);
      }

      // Velocities: the same particles as the contacts just resolved and the next prediction (no barrier).
      if (lead) t0 = Clock::now();
      updateVelocities(t, T(1) / dt);
      if (lead) tm.velocities += msSince(t0);
    }
    t.barrier();

    // Rotations for skinning when the shape-matching block is only kept for them.
    if (model_.rotation_block >= 0 && !model_.blocks[model_.rotation_block].solve) {
      if (lead) t0 = Clock::now();
      updateSkinningRotations(t, ctx);
      if (lead) tm.constraints += msSince(t0);
    }

    if (lead) t0 = Clock::now();
    updateRadii(t, p, in);
    if (lead) tm.volume += msSince(t0);

    distanceResiduals(t, p, dt);
  }

  // Substep start: prediction, kinematic (w = 0: prediction only records x_prev) particles then placed on their
  // path; every multiplier back to zero; the Chebyshev iterate one back.
  void predictSubstep(const Team& t, const PbdStepParams<T>& p, const PbdFrameInput<T>& in, T dt, T t_end) {
    const std::int64_t ni = std::int64_t(model_.size());
    const std::int64_t na = std::int64_t(in.attach_ids.size());
    const T damp = std::exp(-p.damping * dt);
    Vec3<T>* x = state_.positions.data();
    Vec3<T>* v = state_.velocities.data();
    const std::vector<Vec3<T>>& kin_from = in.kinematic_from_positions ? kinematic_from_ : in.kinematic_from;
    for (std::int64_t i = t.begin(ni), i1 = t.end(ni); i < i1; ++i) {
      pbd::predictParticle(x[i], v[i], x_prev_[i], w_[i], p.gravity, damp, dt);
      const std::int32_t k = kinematic_of_[i];
      if (k >= 0) x[i] = pbd::lerp(kin_from[k], in.kinematic_to[k], t_end);
    }
    for (auto& l : lambda_) {
      const std::int64_t m = std::int64_t(l.size());
      std::fill(l.begin() + t.begin(m), l.begin() + t.end(m), Vec3<T>());
    }
    std::fill(attach_lambda_.begin() + t.begin(na), attach_lambda_.begin() + t.end(na), Vec3<T>());
    if (p.chebyshev_rho > T(0)) startChebyshev(t, ni);
  }

  // One iteration's projections of every solved block: Jacobi (project, then gather per particle) or Gauss-Seidel
  // colour by colour. Returns whether the last phase was per particle (the next per-particle one needs no barrier).
  bool projectBlocks(const Team& t, const pbd::SolveContext<T>& ctx, pbd::GoalCorrection<T>* goals) {
    bool particle_phase = false;
    for (std::size_t bi = 0; bi < model_.blocks.size(); ++bi) {
      if (!model_.blocks[bi].solve) continue;
      if (particle_phase) t.barrier();
      if (ctx.jacobi) {
        projectJacobiBlock(t, bi, ctx, goals);
        particle_phase = true;
      } else {
        projectColoredBlock(t, bi, ctx, goals);
        particle_phase = false;
      }
    }
    return particle_phase;
  }

  void projectJacobiBlock(const Team& t, std::size_t bi, const pbd::SolveContext<T>& ctx,
                          pbd::GoalCorrection<T>* goals) {
    const std::int64_t ni = std::int64_t(model_.size());
    Vec3<T>* x = state_.positions.data();
    const pbd::BlockView<T>& view = views_[bi];
    const std::int32_t nc = std::int32_t(model_.blocks[bi].count());
    std::int32_t q0 = std::int32_t(t.begin(nc)), q1 = std::int32_t(t.end(nc));
    if (t.size() == split_parts_ && t.id() < split_parts_) {
      q0 = jacobi_split_[bi][std::size_t(t.id())];
      q1 = jacobi_split_[bi][std::size_t(t.id()) + 1];
    }
    projectRange(view, nullptr, q0, q1, ctx, goals);
    t.barrier();
    for (std::int64_t i = t.begin(ni), i1 = t.end(ni); i < i1; ++i)
      x[i] += pbd::gatherCorrection(view, std::int32_t(i));
  }

  void projectColoredBlock(const Team& t, std::size_t bi, const pbd::SolveContext<T>& ctx,
                           pbd::GoalCorrection<T>* goals) {
    const pbd::BlockView<T>& view = views_[bi];
    const ConstraintColoring& col = model_.blocks[bi].coloring;
    for (int k = 0; k < col.colorCount(); ++k) {
      const std::int32_t c0 = col.color_offsets[k], c1 = col.color_offsets[k + 1];
      std::int32_t q0 = c0 + std::int32_t(t.begin(c1 - c0)), q1 = c0 + std::int32_t(t.end(c1 - c0));
      if (t.size() == split_parts_ && t.id() < split_parts_) {
        const std::int32_t* sp =
            &color_split_[bi][std::size_t(k) * std::size_t(split_parts_ + 1) + std::size_t(t.id())];
        q0 = c0 + sp[0];
        q1 = c0 + sp[1];
      }
      projectRange(view, col.order.data(), q0, q1, ctx, goals);
      t.barrier();
    }
  }

  // The attachments (grasped points pulled towards their tool), after the blocks.
  void projectAttachments(const Team& t, const PbdStepParams<T>& p, const PbdFrameInput<T>& in, T dt, T t_end,
                          bool particle_phase) {
    const std::int64_t na = std::int64_t(in.attach_ids.size());
    if (na <= 0) return;
    Vec3<T>* x = state_.positions.data();
    if (particle_phase) t.barrier();
    for (std::int64_t k = t.begin(na), k1 = t.end(na); k < k1; ++k) {
      const std::int32_t id = in.attach_ids[k];
      pbd::projectAttachment(x[id], w_[id], pbd::lerp(in.attach_from[k], in.attach_to[k], t_end),
                             in.attach_compliance[k], p.xpbd, dt, attach_lambda_[k]);
    }
    t.barrier();
  }

  // Chebyshev: every projection of the iteration is done (the gather's or the attachments' barrier), so the
  // multipliers are blended here, and each position before its contacts (as the CUDA contact kernels do).
  void finishIteration(const Team& t, const PbdStepParams<T>& p, const PbdFrameInput<T>& in, int it, T t_start, T t_end,
                       T& cheb_weight) {
    const std::int64_t ni = std::int64_t(model_.size());
    const std::int64_t na = std::int64_t(in.attach_ids.size());
    const int nt = int(in.tools_from.size());
    Vec3<T>* x = state_.positions.data();
    const T* r = state_.radii.data();
    const std::vector<T>& inset = model_.contact_inset;  // empty: the balls meet the static colliders
    const bool cheb = p.chebyshev_rho > T(0);
    const pbd::ChebyshevMode mode =
        cheb ? pbd::chebyshevIteration(it, p.iterations, p.chebyshev_rho, cheb_weight) : pbd::ChebyshevMode::Off;
    const bool on = mode != pbd::ChebyshevMode::Off;
    if (on) blendMultipliers(t, na, cheb_weight, mode);
    for (std::int64_t i = t.begin(ni), i1 = t.end(ni); i < i1; ++i)
      x[i] = pbd::endIteration(x[i], w_[i] > T(0), on ? &cheb_.x1[i] : nullptr, on ? &cheb_.x2[i] : nullptr,
                               cheb_weight, mode, [&](const Vec3<T>& q) {
                                 return pbd::resolveContacts(
                                     q, r[i], inset.empty() ? T(0) : inset[i], &x_prev_[i], model_.planes.data(),
                                     int(model_.planes.size()), model_.boxes.data(), int(model_.boxes.size()),
                                     in.tools_from.data(), in.tools_to.data(), nt, t_start, t_end);
                               });
  }

  void updateVelocities(const Team& t, T inv_dt) {
    const std::int64_t ni = std::int64_t(model_.size());
    const Vec3<T>* x = state_.positions.data();
    Vec3<T>* v = state_.velocities.data();
    for (std::int64_t i = t.begin(ni), i1 = t.end(ni); i < i1; ++i) v[i] = (x[i] - x_prev_[i]) * inv_dt;
  }

  void updateSkinningRotations(const Team& t, const pbd::SolveContext<T>& ctx) {
    const pbd::BlockView<T>& view = views_[std::size_t(model_.rotation_block)];
    for (std::int64_t c = t.begin(view.count), c1 = t.end(view.count); c < c1; ++c)
      pbd::updateClusterRotation(view, int(c), ctx);
  }

  // Residuals of the distance constraints (after the last substep, with its multipliers), summed in order by
  // summarize().
  void distanceResiduals(const Team& t, const PbdStepParams<T>& p, T dt) {
    const Vec3<T>* x = state_.positions.data();
    std::size_t off = 0;
    for (std::size_t bi = 0; bi < model_.blocks.size(); ++bi) {
      if (model_.blocks[bi].kind != PbdConstraintKind::Distance || !model_.blocks[bi].solve) continue;
      const pbd::BlockView<T>& view = views_[bi];
      for (std::int64_t c = t.begin(view.count), c1 = t.end(view.count); c < c1; ++c)
        residual_[off + std::size_t(c)] = double(pbd::distanceResidual(view, int(c), x, p.xpbd, dt));
      off += std::size_t(view.count);
    }
  }

  // Chebyshev iterates (positions, every block's multipliers, the attachments'), sized for this frame.
  void sizeChebyshev(std::size_t attachments) {
    cheb_.x1.resize(model_.size());
    cheb_.x2.resize(model_.size());
    cheb_.l1.resize(lambda_.size());
    cheb_.l2.resize(lambda_.size());
    for (std::size_t b = 0; b < lambda_.size(); ++b) {
      cheb_.l1[b].resize(lambda_[b].size());
      cheb_.l2[b].resize(lambda_[b].size());
    }
    cheb_.a1.resize(attachments);
    cheb_.a2.resize(attachments);
  }

  // Substep start, after the prediction: the iterate one back is the predicted position (the multipliers' is
  // zero, which pbd::chebyshevMultiplier knows).
  void startChebyshev(const Team& t, std::int64_t ni) {
    const Vec3<T>* x = state_.positions.data();
    for (std::int64_t i = t.begin(ni), i1 = t.end(ni); i < i1; ++i) cheb_.x1[i] = x[i];
  }

  // Every multiplier's Chebyshev step; each thread its own range of each array (the projections are done).
  void blendMultipliers(const Team& t, std::int64_t na, T weight, pbd::ChebyshevMode mode) {
    for (std::size_t b = 0; b < lambda_.size(); ++b) {
      if (!model_.blocks[b].solve) continue;
      Vec3<T>* l = lambda_[b].data();
      const std::int64_t m = std::int64_t(lambda_[b].size());
      for (std::int64_t k = t.begin(m), k1 = t.end(m); k < k1; ++k)
        pbd::chebyshevMultiplier(l[k], cheb_.l1[b][k], cheb_.l2[b][k], weight, mode);
    }
    for (std::int64_t k = t.begin(na), k1 = t.end(na); k < k1; ++k)
      pbd::chebyshevMultiplier(attach_lambda_[k], cheb_.a1[k], cheb_.a2[k], weight, mode);
  }

  // Frame summary on the calling thread, after the team: residuals in constraint order, the first non-finite
  // particle, volume statistics.
  void summarize(PbdFrameStats& st) const {
    double rmax = 0, rsum = 0;
    for (double res : residual_) {
      rmax = std::max(rmax, res);
      rsum += res * res;
    }
    st.residual_max = rmax;
    st.residual_rms = residual_.empty() ? 0.0 : std::sqrt(rsum / double(residual_.size()));
    const std::size_t n = model_.size();
    for (std::size_t i = 0; i < n; ++i)
      if (!isFinite(state_.positions[i]) || !isFinite(state_.velocities[i]) ||
          !std::isfinite(double(state_.radii[i]))) {
        st.finite = false;
        st.failure_particle = std::int64_t(i);
        break;
      }
    st.volume_active = 0;
    st.max_radius_ratio = 1.0;
    for (std::size_t i = 0; i < n; ++i) {
      st.volume_active += active_[i];
      if (model_.rest_radii[i] > T(0))
        st.max_radius_ratio = std::max(st.max_radius_ratio, double(state_.radii[i] / model_.rest_radii[i]));
    }
  }

  pbd::BlockView<T> blockView(std::size_t bi) {
    const PbdConstraintBlock<T>& b = model_.blocks[bi];
    pbd::BlockView<T> v;
    v.kind = int(b.kind);
    v.count = int(b.count());
    v.stiffness = b.stiffness;
    v.offsets = b.offsets.data();
    v.ids = b.ids.data();
    v.rest = b.rest.data();
    v.rest_vec = b.rest_vec.data();
    v.compliance = b.compliance.data();
    v.jacobi_scale = b.jacobi_scale.data();
    v.particle_offsets = b.particle_offsets.data();
    v.particle_slots = b.particle_slots.data();
    v.lambda = lambda_[bi].data();
    v.slot_corr = slot_corr_[bi].data();
    v.alpha_tilde = alpha_tilde_[bi].data();
    return v;
  }

  int teamThreads() const {
    if (solved_slots_ < kTeamMinSlots) return 1;
    return int(std::max<std::int64_t>(1, std::min<std::int64_t>(threadCount(), solved_slots_ / kTeamSlotsPerThread)));
  }

  void planTeam(int threads) {
    goal_scratch_.assign(std::size_t(threads) * std::max<std::size_t>(max_cluster_, 1), pbd::GoalCorrection<T>{});
    planSplits(threads);
  }

  // Static splits of every projection phase over `parts` threads, balanced by constraint weight: Jacobi by
  // constraint index, Gauss-Seidel per colour along the colour's order (constraints of one colour are
  // independent, so who projects which does not change the result).
  void planSplits(int parts) {
    split_parts_ = parts;
    jacobi_split_.assign(model_.blocks.size(), {});
    color_split_.assign(model_.blocks.size(), {});
    std::vector<std::int64_t> prefix;
    for (std::size_t bi = 0; bi < model_.blocks.size(); ++bi) {
      const auto& b = model_.blocks[bi];
      const auto weight = [&](std::int32_t c) { return constraintWeight(b.kind, b.offsets[c + 1] - b.offsets[c]); };
      prefix.assign(1, 0);
      for (std::size_t c = 0; c < b.count(); ++c) prefix.push_back(prefix.back() + weight(std::int32_t(c)));
      jacobi_split_[bi].resize(std::size_t(parts) + 1);
      balancedSplit(prefix, parts, jacobi_split_[bi].data());
      const ConstraintColoring& col = b.coloring;
      color_split_[bi].resize(std::size_t(col.colorCount()) * std::size_t(parts + 1));
      for (int k = 0; k < col.colorCount(); ++k) {
        prefix.assign(1, 0);
        for (std::int32_t q = col.color_offsets[k]; q < col.color_offsets[k + 1]; ++q)
          prefix.push_back(prefix.back() + weight(col.order[q]));
        balancedSplit(prefix, parts, &color_split_[bi][std::size_t(k) * std::size_t(parts + 1)]);
      }
    }
  }

  // Local volume preservation (physics/pbd_volume.h): spheres near a tool get the radius at which their
  // power-cell volume is back at rest; the rest return to their rest radius. Jacobi passes (read radii,
  // write radii_next) make it independent of the order.
  void updateRadii(const Team& t, const PbdStepParams<T>& p, const PbdFrameInput<T>& in) {
    const std::size_t n = model_.size();
    const std::int64_t ni = std::int64_t(n);
    const bool have_volume =
        p.volume_preservation && model_.rest_cell_volume.size() == n && !model_.ball_samples.empty();
    const Vec3<T>* x = state_.positions.data();
    for (std::int64_t i = t.begin(ni), i1 = t.end(ni); i < i1; ++i) {
      std::uint8_t a = 0;
      if (have_volume) {
        if (p.volume_influence < T(0)) {
          a = 1;
        } else {
          for (int k = 0; k < in.volumeToolCount() && !a; ++k)
            if (pbd::capsuleDistance(x[i], in.tools_to[k]) <= model_.rest_radii[i] + p.volume_influence) a = 1;
        }
      }
      active_[i] = a;
    }
    // Each pass reads every sphere's radius from the previous one (the first pass: the frame's start) and only
    // its own spheres' active flags (the same split as above: no barrier before it).
    for (int pass = 0; pass < (have_volume ? p.volume_passes : 1); ++pass) {
      for (std::int64_t i = t.begin(ni), i1 = t.end(ni); i < i1; ++i) {
        const T r0 = model_.rest_radii[i];
        if (!active_[i]) {
          radii_next_[i] = r0;
          continue;
        }
        const std::int32_t b = model_.overlap_offsets[i], e = model_.overlap_offsets[i + 1];
        radii_next_[i] =
            pbd::radiusForCellVolume(x[i], r0, r0 * p.max_radius_growth, model_.rest_cell_volume[i], x,
                                     state_.radii.data(), model_.overlap_ids.data() + b, e - b,
                                     model_.ball_samples.data(), int(model_.ball_samples.size()), p.bisection_steps);
      }
      t.barrier();
      if (t.lead()) state_.radii.swap(radii_next_);
      t.barrier();
    }
  }

  bool has_coloring_ = true;  // Gauss-Seidel needs every solved block coloured (pbdModelHasColoring)
  PbdModel<T> model_;
  PbdState<T> state_;
  std::vector<Vec3<T>> x_prev_;
  std::vector<T> w_;
  std::vector<T> radii_next_;
  std::vector<std::uint8_t> active_;        // spheres whose radius is solved this frame
  std::vector<std::int32_t> kinematic_of_;  // per particle: its index in this frame's kinematic list, or -1
  std::vector<Vec3<T>> kinematic_from_;     // the frame's start positions (PbdFrameInput::kinematic_from_positions)
  std::vector<std::vector<Vec3<T>>> lambda_;
  std::vector<std::vector<Vec3<T>>> slot_corr_;
  std::vector<std::vector<T>> alpha_tilde_;  // per block and multiplier: compliance / dt^2 of this frame
  std::vector<Vec3<T>> attach_lambda_;
  struct {
    std::vector<Vec3<T>> x1, x2;               // positions one and two iterations back
    std::vector<std::vector<Vec3<T>>> l1, l2;  // per block: multipliers one and two back
    std::vector<Vec3<T>> a1, a2;               // attachment multipliers one and two back
  } cheb_;                                     // Chebyshev iterates (PbdStepParams::chebyshev_rho > 0)
  std::vector<pbd::BlockView<T>> views_;
  std::vector<double> residual_;                         // per solved distance constraint, this frame
  std::int64_t solved_slots_ = 0;                        // constraint slots of the solved blocks (one iteration's work)
  int split_parts_ = 0;                                  // team size the splits and scratch are planned for
  std::vector<std::vector<std::int32_t>> jacobi_split_;  // per block: parts + 1 constraint indices
  std::vector<std::vector<std::int32_t>> color_split_;   // per block: per colour parts + 1 positions in the colour
  std::size_t max_cluster_ = 0;                          // most members of a solved shape-matching cluster
  bool goals_distinct_ = true;                           // no particle twice in one cluster
  std::vector<pbd::GoalCorrection<T>> goal_scratch_;     // per thread: max_cluster_ members' goal corrections
  TeamRunner team_;
};

}  // namespace

template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdCpuBackend() {
  return std::make_unique<PbdCpuBackend<T>>();
}

template std::unique_ptr<PbdBackend<float>> makePbdCpuBackend<float>();
template std::unique_ptr<PbdBackend<double>> makePbdCpuBackend<double>();

void setPbdReferenceLoop(bool reference) { g_reference_loop = reference; }

}  // namespace inc::cpu
