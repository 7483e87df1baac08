// The arguments of the whole-frame PBD kernels (single block and thread-block cluster): raw device views of the model, the frame's inputs and step parameters.
#pragma once

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

}  // namespace inc::cuda
