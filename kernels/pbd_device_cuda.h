// In-place device patching of the CUDA PBD backend's model: appended particles, constraint blocks rewritten on the
// device, incidence by radix sort or from the caller.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "model/pbd_model.h"

namespace inc::cuda {

// Device pointers of the particle arrays a topology change writes. Valid until the next reserveParticles
// that grows (or setModel); the first `n` entries are live, `capacity` are allocated.
template <typename T>
struct PbdDeviceParticles {
  int n = 0;
  std::size_t capacity = 0;
  Vec3<T>* rest = nullptr;  // m
  Vec3<T>* x = nullptr;     // m
  Vec3<T>* v = nullptr;     // m/s
  T* mass = nullptr;        // kg
  T* inv_mass = nullptr;    // 1/kg, 0 = fixed
};

// Device pointers of one fixed-arity constraint block (Distance: 2 ids, Bending/TetVolume: 4) with room for
// `capacity` constraints.
template <typename T>
struct PbdDeviceBlock {
  int arity = 0;
  std::size_t capacity = 0;
  std::int32_t* ids = nullptr;  // arity per constraint
  T* rest = nullptr;            // one per constraint
  T* compliance = nullptr;      // one per constraint
};

// Device pointers of one block's particle -> slot CSR, for a caller that derives it itself
// (commitBlockIncidence). particle_offsets has n + 1 entries (n: the particle count when reserved).
struct PbdDeviceIncidence {
  std::size_t slot_capacity = 0;
  std::int32_t* particle_offsets = nullptr;
  std::int32_t* particle_slots = nullptr;
};

// The patch API of the CUDA PBD backend (obtain it with pbdDevicePatch). All work is enqueued on the backend's
// stream (ordered with the legacy default stream, which other kernels of this library use) without a host
// synchronisation, except where a buffer must grow: reserveParticles and reserveBlock reallocate (the live
// prefix copied on the device) only when the request exceeds the capacity, growing geometrically (x 2), and
// that is the patch API's only host synchronisation.
template <typename T>
class PbdDevicePatch {
 public:
  virtual ~PbdDevicePatch() = default;
  virtual PbdDeviceParticles<T> deviceParticles() = 0;
  // Room for `particles` particles (x, v, rest, masses, inverse masses, radii, rotations, scratch).
  virtual void reserveParticles(std::size_t particles) = 0;
  // The caller has written particles [n, n_new) of rest/x/v/mass (within capacity) and possibly changed the
  // masses of live ones: inverse masses := fixed ? 0 : 1 / mass for all n_new particles (fixed: one byte per
  // particle, device pointer); new particles get radius 0 and the identity rotation. n_new >= n.
  virtual void appendParticles(int n_new, const std::uint8_t* fixed_dev) = 0;
  // Room for `constraints` constraints of block b (a Distance, Bending or TetVolume block).
  virtual PbdDeviceBlock<T> reserveBlock(int block, std::size_t constraints) = 0;
  // The caller has written constraints [0, count) of block b (ids, rest, compliance; within capacity):
  // offsets, the particle -> slot CSR (device radix sort, slots ascending per particle: the host's order),
  // the Jacobi scales (from the current inverse masses: call after appendParticles) and the multipliers are
  // rebuilt on the device. The block's colouring is dropped: Jacobi only (advanceFrame throws for
  // Gauss-Seidel on a patched model).
  virtual void commitBlock(int block, int count) = 0;
  // Room for the particle -> slot CSR of `constraints` constraints of block b over the current particles
  // (call after appendParticles; reallocates only beyond the capacity, like reserveBlock).
  virtual PbdDeviceIncidence reserveIncidence(int block, std::size_t constraints) = 0;
  // commitBlock for a caller that has also written the block's particle -> slot CSR into the reserveIncidence
  // buffers (slots ascending per particle, particle_offsets[n] = arity * count): everything commitBlock does
  // (offsets, Jacobi scales from that CSR and the current inverse masses, multipliers reset, colouring dropped)
  // except the sort. Throws when the CSR's buffers were not reserved for this count and particle count.
  virtual void commitBlockIncidence(int block, int count) = 0;
  // The residual/finiteness summary (one small download and a synchronisation) every k-th frame only
  // (k >= 1; default 1). Frames without it report finite = true and residual 0.
  virtual void setSummaryEvery(int k) = 0;
  // The current model's block on the host (ids, offsets, rest, compliance, particle CSR, Jacobi scales), for
  // tests. Synchronises.
  virtual PbdConstraintBlock<T> downloadBlock(int block) const = 0;
  virtual std::vector<T> downloadInverseMasses() const = 0;
  // Host convenience for tests: uploads then commits (reserveBlock + copy + commitBlock).
  virtual void setBlockFromHost(int block, const std::vector<std::int32_t>& ids, const std::vector<T>& rest,
                                const std::vector<T>& compliance) = 0;
  // Host convenience for tests: uploads whole particle arrays (n_new >= n entries each; reserves room) and
  // calls appendParticles(n_new, fixed).
  virtual void appendParticlesFromHost(const std::vector<Vec3<T>>& rest, const std::vector<Vec3<T>>& x,
                                       const std::vector<Vec3<T>>& v, const std::vector<T>& mass,
                                       const std::vector<std::uint8_t>& fixed) = 0;
};

// The patch API of a CUDA PBD backend; nullptr for any other backend.
template <typename T>
PbdDevicePatch<T>* pbdDevicePatch(PbdBackend<T>& backend);

}  // namespace inc::cuda
