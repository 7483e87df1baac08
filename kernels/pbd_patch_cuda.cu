// The CUDA PBD backend's topology patches (PbdDevicePatch): particles appended and constraint blocks rewritten on the
// device after a tear, their incidence by radix sort, the live counts a captured frame reads.
#include <cub/cub.cuh>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "kernels/pbd_backend_cuda.cuh"
#include "physics/tearing_rebuild.h"

namespace inc::cuda {

namespace {

// What uploadLive writes to live_: the particle count, then each block's constraint count (k entries).
struct LiveCounts {
  int v[1 + kMaxLiveBlocks];
  int k;
};
__global__ void setLiveKernel(LiveCounts c, int* live) {
  if (int(threadIdx.x) < c.k) live[threadIdx.x] = c.v[threadIdx.x];
}

// appendParticles in one launch: inverse masses of all n1 particles (the split ones changed mass), and the
// appended ones [n0, n1) start with no radius, no rotation and inactive.
template <typename T>
__global__ void appendParticlesKernel(int n0, int n1, const T* mass, const std::uint8_t* fixed, T* inv_mass, T* rest_r,
                                      T* r, T* r_next, pbd::Quat<T>* rot, std::uint8_t* active) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n1) return;
  inv_mass[i] = fixed[i] ? T(0) : T(1) / mass[i];
  if (i < n0) return;
  rest_r[i] = T(0);
  r[i] = T(0);
  r_next[i] = T(0);
  rot[i] = pbd::Quat<T>{};
  active[i] = 0;
}

__global__ void slotIotaKernel(int slots, const std::int32_t* ids, std::uint32_t* keys, std::int32_t* vals) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q >= slots) return;
  keys[q] = std::uint32_t(ids[q]);
  vals[q] = q;
}

// particle_offsets[p] = first sorted slot of particle p (p = 0 .. n): a binary search per particle.
__global__ void csrOffsetsKernel(int n, const std::uint32_t* sorted, int slots, std::int32_t* offsets) {
  const int p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p > n) return;
  offsets[p] = std::int32_t(tear::lowerBound<std::uint32_t>(sorted, slots, std::uint32_t(p)));
}

// A patched block's derived arrays in one launch (after its particle -> slot CSR): constraint offsets (count + 1),
// Jacobi scales and zeroed multipliers. Not slot_corr: every Jacobi projection writes all of its block's slots
// before the gather reads them.
template <typename T>
__global__ void commitBlockKernel(int count, int arity, const std::int32_t* ids, const std::int32_t* particle_offsets,
                                  const T* inv_mass, std::int32_t* offsets, T* scale, Vec3<T>* lambda) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c > count) return;
  offsets[c] = arity * c;
  if (c == count) return;
  const T sc = tear::jacobiScaleOf(ids, arity, c, particle_offsets, inv_mass);
  for (int k = 0; k < arity; ++k) scale[arity * c + k] = sc;
  lambda[c] = Vec3<T>();
}

inline int blockArity(PbdConstraintKind k) {
  if (k == PbdConstraintKind::Distance) return 2;
  if (k == PbdConstraintKind::Bending || k == PbdConstraintKind::TetVolume) return 4;
  return 0;
}

}  // namespace

template <typename T>
PbdDeviceParticles<T> PbdCudaBackend<T>::deviceParticles() {
  PbdDeviceParticles<T> d;
  d.n = n_;
  d.capacity = std::min({capacityOf(rest_positions_), capacityOf(x_), capacityOf(v_), capacityOf(masses_),
                         capacityOf(inv_mass_), capacityOf(w_), capacityOf(x_prev_), capacityOf(rest_radii_),
                         capacityOf(radii_), capacityOf(radii_next_), capacityOf(rotations_), capacityOf(active_)});
  d.rest = rest_positions_.data();
  d.x = x_.data();
  d.v = v_.data();
  d.mass = masses_.data();
  d.inv_mass = inv_mass_.data();
  return d;
}

template <typename T>
void PbdCudaBackend<T>::reserveParticles(std::size_t particles) {
  const std::size_t keep = std::size_t(n_);
  bool grew = false;
  grew |= growKeep(rest_positions_, particles, keep);
  grew |= growKeep(x_, particles, keep);
  grew |= growKeep(v_, particles, keep);
  grew |= growKeep(x_prev_, particles, keep);
  grew |= growKeep(masses_, particles, keep);
  grew |= growKeep(inv_mass_, particles, keep);
  grew |= growKeep(w_, particles, keep);
  grew |= growKeep(rest_radii_, particles, keep);
  grew |= growKeep(radii_, particles, keep);
  grew |= growKeep(radii_next_, particles, keep);
  grew |= growKeep(rotations_, particles, keep);
  grew |= growKeep(active_, particles, keep);
  if (grew) ++topo_version_;
}

template <typename T>
void PbdCudaBackend<T>::appendParticles(int n_new, const std::uint8_t* fixed_dev) {
  if (has_inset_) throw InputError("pbd patch", "contact_inset", "a model with contact insets cannot gain particles");
  if (n_new < n_) throw InputError("pbd patch", "particles", "appendParticles cannot remove particles");
  if (std::size_t(n_new) > deviceParticles().capacity)
    throw InputError("pbd patch", "particles", "call reserveParticles first (" + std::to_string(n_new) + " particles)");
  if (have_volume_data_ && n_new > n_)
    throw InputError("pbd patch", "volume", "models with volume-preservation data cannot grow on the device");
  const std::size_t m = std::size_t(n_new);
  for (auto* b : {&rest_positions_, &x_, &v_, &x_prev_}) b->resize(m);
  for (auto* b : {&masses_, &inv_mass_, &w_, &rest_radii_, &radii_, &radii_next_}) b->resize(m);
  rotations_.resize(m);
  active_.resize(m);
  if (n_new > 0) {
    appendParticlesKernel<T><<<blocksFor(n_new), kThreads, 0, stream_>>>(
        n_, n_new, masses_.data(), fixed_dev, inv_mass_.data(), rest_radii_.data(), radii_.data(), radii_next_.data(),
        rotations_.data(), active_.data());
    INC_CUDA_LAUNCH("pbd patch particles");
  }
  host_rest_radii_.resize(m, T(0));
  n_ = n_new;
  updateStaging();
  live_dirty_ = true;  // the frame's kernels read the count from live_ (no re-capture unless its bucket changes)
}

template <typename T>
PbdDeviceBlock<T> PbdCudaBackend<T>::reserveBlock(int block, std::size_t constraints) {
  DeviceBlock<T>& d = patchBlock(block);
  const int a = blockArity(d.kind);
  const std::size_t c = std::size_t(d.count);
  bool grew = false;
  grew |= growKeep(d.ids, std::size_t(a) * constraints, std::size_t(a) * c);
  grew |= growKeep(d.rest, constraints, c);
  grew |= growKeep(d.compliance, constraints, c);
  if (grew) ++topo_version_;
  PbdDeviceBlock<T> r;
  r.arity = a;
  r.capacity = std::min({capacityOf(d.ids) / std::size_t(a), capacityOf(d.rest), capacityOf(d.compliance)});
  r.ids = d.ids.data();
  r.rest = d.rest.data();
  r.compliance = d.compliance.data();
  return r;
}

template <typename T>
void PbdCudaBackend<T>::commitBlock(int block, int count) {
  commit(block, count, false);
}

template <typename T>
PbdDeviceIncidence PbdCudaBackend<T>::reserveIncidence(int block, std::size_t constraints) {
  DeviceBlock<T>& d = patchBlock(block);
  const std::size_t slots = std::size_t(blockArity(d.kind)) * constraints;
  // No content to keep: the caller rewrites both arrays before commitBlockIncidence.
  if (growKeep(d.particle_slots, std::max<std::size_t>(slots, 1), 0) |
      growKeep(d.particle_offsets, std::size_t(n_) + 1, 0))
    ++topo_version_;
  PbdDeviceIncidence r;
  r.slot_capacity = capacityOf(d.particle_slots);
  r.particle_offsets = d.particle_offsets.data();
  r.particle_slots = d.particle_slots.data();
  return r;
}

template <typename T>
void PbdCudaBackend<T>::commitBlockIncidence(int block, int count) {
  commit(block, count, true);
}

template <typename T>
void PbdCudaBackend<T>::setSummaryEvery(int k) {
  if (k < 1) throw InputError("pbd patch", "summary_every", "must be >= 1");
  summary_every_ = k;
}

template <typename T>
PbdConstraintBlock<T> PbdCudaBackend<T>::downloadBlock(int block) const {
  if (block < 0 || std::size_t(block) >= blocks_.size()) throw InputError("pbd patch", "block", "out of range");
  INC_CUDA(cudaStreamSynchronize(stream_));
  const DeviceBlock<T>& d = blocks_[std::size_t(block)];
  PbdConstraintBlock<T> b;
  b.kind = d.kind;
  b.solve = d.solve;
  b.stiffness = d.stiffness;
  b.offsets = d.offsets.download();
  b.ids = d.ids.download();
  b.rest = d.rest.download();
  b.rest_vec = d.rest_vec.download();
  b.compliance = d.compliance.download();
  b.particle_offsets = d.particle_offsets.download();
  b.particle_slots = d.particle_slots.download();
  b.jacobi_scale = d.jacobi_scale.download();
  return b;
}

template <typename T>
std::vector<T> PbdCudaBackend<T>::downloadInverseMasses() const {
  INC_CUDA(cudaStreamSynchronize(stream_));
  return inv_mass_.download();
}

template <typename T>
void PbdCudaBackend<T>::setBlockFromHost(int block, const std::vector<std::int32_t>& ids, const std::vector<T>& rest,
                                         const std::vector<T>& compliance) {
  const int a = blockArity(patchBlock(block).kind);
  if (rest.size() != compliance.size() || ids.size() != std::size_t(a) * rest.size())
    throw InputError("pbd patch", "block", "ids, rest and compliance sizes do not match the block's arity");
  for (std::int32_t p : ids)
    if (p < 0 || p >= n_) throw InputError("pbd patch", "ids", "particle index out of range");
  const PbdDeviceBlock<T> r = reserveBlock(block, rest.size());
  INC_CUDA(cudaStreamSynchronize(stream_));
  if (!ids.empty()) {
    INC_CUDA(cudaMemcpy(r.ids, ids.data(), ids.size() * sizeof(std::int32_t), cudaMemcpyHostToDevice));
    INC_CUDA(cudaMemcpy(r.rest, rest.data(), rest.size() * sizeof(T), cudaMemcpyHostToDevice));
    INC_CUDA(cudaMemcpy(r.compliance, compliance.data(), compliance.size() * sizeof(T), cudaMemcpyHostToDevice));
  }
  commitBlock(block, int(rest.size()));
}

template <typename T>
void PbdCudaBackend<T>::appendParticlesFromHost(const std::vector<Vec3<T>>& rest, const std::vector<Vec3<T>>& x,
                                                const std::vector<Vec3<T>>& v, const std::vector<T>& mass,
                                                const std::vector<std::uint8_t>& fixed) {
  const std::size_t m = rest.size();
  if (has_inset_) throw InputError("pbd patch", "contact_inset", "a model with contact insets cannot gain particles");
  if (x.size() != m || v.size() != m || mass.size() != m || fixed.size() != m || m < std::size_t(n_))
    throw InputError("pbd patch", "particles", "whole arrays of one size >= the particle count expected");
  for (T mm : mass)
    if (!(mm > T(0))) throw InputError("pbd patch", "mass", "must be > 0");
  reserveParticles(m);
  INC_CUDA(cudaStreamSynchronize(stream_));
  if (m) {
    INC_CUDA(cudaMemcpy(rest_positions_.data(), rest.data(), m * sizeof(Vec3<T>), cudaMemcpyHostToDevice));
    INC_CUDA(cudaMemcpy(x_.data(), x.data(), m * sizeof(Vec3<T>), cudaMemcpyHostToDevice));
    INC_CUDA(cudaMemcpy(v_.data(), v.data(), m * sizeof(Vec3<T>), cudaMemcpyHostToDevice));
    INC_CUDA(cudaMemcpy(masses_.data(), mass.data(), m * sizeof(T), cudaMemcpyHostToDevice));
  }
  fixed_scratch_.upload(fixed);
  appendParticles(int(m), fixed_scratch_.data());
  INC_CUDA(cudaStreamSynchronize(stream_));  // fixed_scratch_ may be overwritten by the next call
}

// commitBlock (caller_csr false: the particle -> slot CSR by a device radix sort) and commitBlockIncidence
// (caller_csr true: the caller wrote it into the reserveIncidence buffers).
template <typename T>
void PbdCudaBackend<T>::commit(int block, int count, bool caller_csr) {
  DeviceBlock<T>& d = patchBlock(block);
  const int a = blockArity(d.kind);
  if (count < 0 || std::size_t(count) > std::min(capacityOf(d.ids) / std::size_t(a), capacityOf(d.rest)) ||
      std::size_t(count) > capacityOf(d.compliance))
    throw InputError("pbd patch", "count", "call reserveBlock first (" + std::to_string(count) + " constraints)");
  const std::size_t cnt = std::size_t(count), slots = std::size_t(a) * cnt;
  // The caller's CSR must not be reallocated here (growKeep with nothing kept would drop it).
  if (caller_csr && (slots > capacityOf(d.particle_slots) || std::size_t(n_) + 1 > capacityOf(d.particle_offsets)))
    throw InputError("pbd patch", "incidence",
                     "call reserveIncidence after appendParticles (" + std::to_string(count) + " constraints)");
  d.ids.resize(slots);
  d.rest.resize(cnt);
  d.compliance.resize(cnt);
  // Derived arrays: no content to keep, so growing them needs no copy (and no synchronisation beyond the
  // one inside the allocation of a larger buffer, which happens only when the block outgrows its capacity).
  if (growKeep(d.offsets, cnt + 1, 0) | growKeep(d.jacobi_scale, slots, 0) | growKeep(d.particle_slots, slots, 0) |
      growKeep(d.lambda, cnt, 0) | growKeep(d.slot_corr, slots, 0) |
      growKeep(d.particle_offsets, std::size_t(n_) + 1, 0))
    ++topo_version_;
  d.offsets.resize(cnt + 1);
  d.jacobi_scale.resize(slots);
  d.particle_slots.resize(slots);
  d.lambda.resize(cnt);
  d.slot_corr.resize(slots);
  d.particle_offsets.resize(std::size_t(n_) + 1);
  d.count = count;
  if (!caller_csr) sortIncidence(d, slots);
  commitBlockKernel<T><<<blocksFor(count + 1), kThreads, 0, stream_>>>(
      count, a, d.ids.data(), d.particle_offsets.data(), inv_mass_.data(), d.offsets.data(), d.jacobi_scale.data(),
      d.lambda.data());
  INC_CUDA_LAUNCH("pbd patch block");
  d.order.resize(0);
  d.color_offsets.assign(1, 0);
  // The summary's reduction partials: room for every block (a block that was empty at setModel may not be).
  const std::size_t need = std::size_t(2 * blocks_.size() + 3) * (kReduceBlocks + 1);
  if (partials_.size() < need) partials_.resize(need);
  patched_ = true;
  live_dirty_ = true;  // as appendParticles: counts travel through live_
}

// particle -> slot CSR: slots sorted by particle with a stable radix sort over the index bits (slots stay
// ascending per particle: the order finalizePbdModel's counting sort gives), offsets by binary search.
template <typename T>
void PbdCudaBackend<T>::sortIncidence(DeviceBlock<T>& d, std::size_t slots) {
  sort_keys_.resize(std::max<std::size_t>(slots, 1));
  sort_keys_out_.resize(std::max<std::size_t>(slots, 1));
  sort_vals_.resize(std::max<std::size_t>(slots, 1));
  if (slots > 0) {
    slotIotaKernel<<<blocksFor(std::int64_t(slots)), kThreads, 0, stream_>>>(int(slots), d.ids.data(),
                                                                             sort_keys_.data(), sort_vals_.data());
    INC_CUDA_LAUNCH("pbd patch slot keys");
    const int end_bit = tear::indexBits(n_);
    std::size_t bytes = 0;
    INC_CUDA(cub::DeviceRadixSort::SortPairs(nullptr, bytes, sort_keys_.data(), sort_keys_out_.data(),
                                             sort_vals_.data(), d.particle_slots.data(), int(slots), 0, end_bit,
                                             stream_));
    cub_temp_.resize(std::max<std::size_t>(bytes, 1));
    INC_CUDA(cub::DeviceRadixSort::SortPairs(cub_temp_.data(), bytes, sort_keys_.data(), sort_keys_out_.data(),
                                             sort_vals_.data(), d.particle_slots.data(), int(slots), 0, end_bit,
                                             stream_));
  }
  csrOffsetsKernel<<<blocksFor(n_ + 1), kThreads, 0, stream_>>>(n_, sort_keys_out_.data(), int(slots),
                                                                d.particle_offsets.data());
  INC_CUDA_LAUNCH("pbd patch particle offsets");
}

template <typename T>
DeviceBlock<T>& PbdCudaBackend<T>::patchBlock(int block) {
  if (block < 0 || std::size_t(block) >= blocks_.size()) throw InputError("pbd patch", "block", "out of range");
  DeviceBlock<T>& d = blocks_[std::size_t(block)];
  if (blockArity(d.kind) == 0)
    throw InputError("pbd patch", "block", "only distance, bending and tet-volume blocks can be patched");
  return d;
}

// Writes live_ when a patch or a new model changed the counts (one launch, ordered before the frame on stream_).
template <typename T>
void PbdCudaBackend<T>::uploadLive() {
  if (!live_dirty_) return;
  LiveCounts c{};
  c.k = 1 + int(blocks_.size());
  c.v[0] = n_;
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi) c.v[1 + bi] = blocks_[bi].count;
  setLiveKernel<<<1, 1 + kMaxLiveBlocks, 0, stream_>>>(c, live_.data());
  INC_CUDA_LAUNCH("pbd live counts");
  live_dirty_ = false;
}

// Defined here, called from the other files of the backend (the class is instantiated in pbd_solver_cuda.cu).
template PbdDeviceParticles<float> PbdCudaBackend<float>::deviceParticles();
template PbdDeviceParticles<double> PbdCudaBackend<double>::deviceParticles();
template void PbdCudaBackend<float>::reserveParticles(std::size_t);
template void PbdCudaBackend<double>::reserveParticles(std::size_t);
template void PbdCudaBackend<float>::appendParticles(int, const std::uint8_t*);
template void PbdCudaBackend<double>::appendParticles(int, const std::uint8_t*);
template PbdDeviceBlock<float> PbdCudaBackend<float>::reserveBlock(int, std::size_t);
template PbdDeviceBlock<double> PbdCudaBackend<double>::reserveBlock(int, std::size_t);
template void PbdCudaBackend<float>::commitBlock(int, int);
template void PbdCudaBackend<double>::commitBlock(int, int);
template PbdDeviceIncidence PbdCudaBackend<float>::reserveIncidence(int, std::size_t);
template PbdDeviceIncidence PbdCudaBackend<double>::reserveIncidence(int, std::size_t);
template void PbdCudaBackend<float>::commitBlockIncidence(int, int);
template void PbdCudaBackend<double>::commitBlockIncidence(int, int);
template void PbdCudaBackend<float>::setSummaryEvery(int);
template void PbdCudaBackend<double>::setSummaryEvery(int);
template PbdConstraintBlock<float> PbdCudaBackend<float>::downloadBlock(int) const;
template PbdConstraintBlock<double> PbdCudaBackend<double>::downloadBlock(int) const;
template std::vector<float> PbdCudaBackend<float>::downloadInverseMasses() const;
template std::vector<double> PbdCudaBackend<double>::downloadInverseMasses() const;
template void PbdCudaBackend<float>::setBlockFromHost(int, const std::vector<std::int32_t>&, const std::vector<float>&,
                                                      const std::vector<float>&);
template void PbdCudaBackend<double>::setBlockFromHost(int, const std::vector<std::int32_t>&,
                                                       const std::vector<double>&, const std::vector<double>&);
template void PbdCudaBackend<float>::appendParticlesFromHost(const std::vector<Vec3<float>>&,
                                                             const std::vector<Vec3<float>>&,
                                                             const std::vector<Vec3<float>>&, const std::vector<float>&,
                                                             const std::vector<std::uint8_t>&);
template void PbdCudaBackend<double>::appendParticlesFromHost(const std::vector<Vec3<double>>&,
                                                              const std::vector<Vec3<double>>&,
                                                              const std::vector<Vec3<double>>&,
                                                              const std::vector<double>&,
                                                              const std::vector<std::uint8_t>&);
template void PbdCudaBackend<float>::uploadLive();
template void PbdCudaBackend<double>::uploadLive();

}  // namespace inc::cuda
