// The arguments of the whole-frame PBD kernels (single block and thread-block cluster): raw device views of the model,
// the frame's inputs and step parameters, the cluster's split of the work.
#pragma once

#include <cstddef>
#include <cstdint>

#include "physics/pbd_block.h"
#include "physics/pbd_collision.h"
#include "physics/pbd_rotation.h"
#include "physics/vec3.h"

namespace inc::cuda {

constexpr int kMaxFusedBlocks = 8;

template <typename T>
struct FusedBlock {
  pbd::BlockView<T> view;
  const std::int32_t* order = nullptr;          // Gauss-Seidel: constraints sorted by colour
  const std::int32_t* color_offsets = nullptr;  // device copy, colors + 1 entries
  int colors = 0;
  int multipliers = 0;
  bool solve = true;
};

template <typename T>
struct FusedFrame {
  int n = 0, substeps = 1, iterations = 1, nblocks = 0;
  Vec3<T>* x = nullptr;
  Vec3<T>* v = nullptr;
  Vec3<T>* x_prev = nullptr;
  const T* w = nullptr;
  const T* r = nullptr;
  const T* inset = nullptr;  // PbdModel::contact_inset (null: none)
  Vec3<T> g;
  T damp = T(1), dt = T(0);
  pbd::SolveContext<T> ctx;
  FusedBlock<T> blocks[kMaxFusedBlocks];
  int n_kin = 0;
  const std::int32_t* kin_ids = nullptr;
  const Vec3<T>* kin_from = nullptr;
  const Vec3<T>* kin_to = nullptr;
  int n_att = 0;
  const std::int32_t* att_ids = nullptr;
  const Vec3<T>* att_from = nullptr;
  const Vec3<T>* att_to = nullptr;
  const T* att_comp = nullptr;
  Vec3<T>* att_lambda = nullptr;
  const pbd::PlaneCollider<T>* planes = nullptr;
  const pbd::BoxCollider<T>* boxes = nullptr;
  const pbd::CapsuleCollider<T>* tools_from = nullptr;
  const pbd::CapsuleCollider<T>* tools_to = nullptr;
  int np = 0, nb = 0, nt = 0;
  bool staged = false;  // positions, inverse masses, masses and rotations copied to dynamic shared memory
};

// The thread-block cluster frame's split of the work (kernels/pbd_cluster_frame.cuh).
//
// Layout: CTA r projects the constraints [c_split[b][r], c_split[b][r+1]) of block b (their slots are the
// contiguous range [s_split[b][r], s_split[b][r+1])) and writes their slot corrections into its own shared
// memory; it owns the particles [r * chunk, (r + 1) * chunk) and gathers their corrections from the CTAs that
// computed them (remote shared-memory reads), then writes the new positions into every CTA's replica. The
// physics calls, their arguments and the gather's summation order are those of the per-launch path, so the
// two paths compute the same numbers.
constexpr int kMaxClusterCtas = 16;
constexpr int kClusterThreads = 1024;

struct ClusterSplit {
  int ctas = 1;
  int chunk = 0;      // particles per CTA (the last may own fewer)
  int max_share = 0;  // most slots any CTA projects in any block (its slot buffer)
  int c_split[kMaxFusedBlocks][kMaxClusterCtas + 1] = {};
  int s_split[kMaxFusedBlocks][kMaxClusterCtas + 1] = {};
  // Per block, in the order of particle_slots: where that slot's correction lives, packed as
  // (CTA << 24) | index in that CTA's slot buffer (planned on the host: no search in the gather).
  const std::int32_t* slot_home[kMaxFusedBlocks] = {};
  long long* profile = nullptr;  // diagnostics: SM cycles per phase kind, per CTA (kClusterProfileSlots each)
};

// Phase kinds of the cycle profile: 0 substep start (predict, kinematic, broadcast, barrier); then per block b
// 1 + 4b: projection, 2 + 4b: barrier after it, 3 + 4b: gather (+ attachments and contacts after the last
// block) and broadcast, 4 + 4b: barrier after it.
constexpr int kClusterProfileSlots = 1 + 4 * kMaxFusedBlocks;

// Dynamic shared memory per CTA: rotations, positions, inverse masses, masses, radii of every particle and the
// CTA's slot buffer.
template <typename T>
inline std::size_t clusterStageBytes(int n, int max_share) {
  return std::size_t(n) * (sizeof(pbd::Quat<T>) + sizeof(Vec3<T>) + 3 * sizeof(T)) +
         std::size_t(max_share) * sizeof(Vec3<T>);
}

}  // namespace inc::cuda
