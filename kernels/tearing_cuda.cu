// CUDA tearing step: the physics/tearing_phases.h bodies as kernels, CUB exclusive sum and DeviceSelect for the split
// list; device-resident sheet with the adjacency and PBD model rebuilt per particle (or by the older radix sorts).
#include "kernels/tearing_cuda.h"

#include <cub/cub.cuh>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <vector>

#include "kernels/cuda_check.h"
#include "kernels/device_buffer.h"
#include "kernels/device_grow.h"
#include "kernels/pbd_device_cuda.h"
#include "kernels/pinned_staging.h"
#include "model/input_error.h"
#include "physics/tearing_phases.h"
#include "physics/tearing_rebuild.h"

namespace inc::cuda {

namespace {

constexpr int kBlock = 256;
inline unsigned gridFor(std::size_t n) { return unsigned((n + kBlock - 1) / kBlock); }

template <typename T>
__global__ void detectKernel(tear::SheetView<T> s, int n, int criterion, T break_strain, std::uint8_t* yield,
                             std::int32_t* partner, Vec3<T>* dir, T* t_pred) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const tear::Detection<T> d = tear::detectYield(s, i, criterion, break_strain);
  yield[i] = d.yield;
  partner[i] = d.partner;
  dir[i] = d.dir;
  t_pred[i] = d.t_pred;
}

// yield_accept (optional): (yield, accept) per particle, reduced to the step's two counts in one pass.
template <typename T>
__global__ void acceptKernel(tear::SheetView<T> s, int n, const std::uint8_t* yield, std::uint32_t seed,
                             std::uint32_t step, std::uint8_t* accept, std::int32_t* accept_i32,
                             int2* yield_accept = nullptr) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const std::uint8_t a = tear::acceptSplit(s, yield, i, seed, step);
  accept[i] = a;
  accept_i32[i] = a;
  if (yield_accept) yield_accept[i] = make_int2(yield[i], a);
}

struct AddInt2 {
  __host__ __device__ int2 operator()(const int2& a, const int2& b) const { return make_int2(a.x + b.x, a.y + b.y); }
};

__global__ void iotaKernel(std::int32_t* out, int n) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) out[i] = i;
}

// Over the compacted list of accepted particles (list set: thread k < count splits list[k]), or over all particles
// (list null, count = n: thread i splits particle i when accepted; no compaction needed). moved / backed (optional):
// per thread.
template <typename T>
__global__ void splitKernel(tear::SheetView<T> s, const std::int32_t* list, int count, const std::uint8_t* accept,
                            const std::int32_t* rank, int n, const std::int32_t* partner, const Vec3<T>* dir,
                            const T* t_pred, bool debris, T range, T t_lo, T t_hi, T min_ratio, std::uint32_t seed,
                            std::uint32_t step, int* moved, int* backed) {
  const int k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= count) return;
  const std::int32_t i = list ? list[k] : k;
  if (!list && !accept[i]) return;
  const tear::SplitResult r = tear::splitParticle(s, i, std::size_t(n) + std::size_t(rank[i]), partner[i], dir[i],
                                                  t_pred[i], debris, range, t_lo, t_hi, min_ratio, seed, step);
  if (moved) moved[k] = r.moved_triangles;
  if (backed) backed[k] = r.backed_off;
}

// Triangle t < nt rebuilt; threads g < zero_n also clear zero_counts (the resident rebuild's particle -> triangle
// counts, accumulated next: one launch fewer than a memset).
template <typename T>
__global__ void triangleKernel(tear::SheetView<T> s, int nt, const std::uint8_t* accept, const Vec3<T>* dir,
                               const std::int32_t* rank, int n, std::int32_t* zero_counts = nullptr, int zero_n = 0) {
  const int t = blockIdx.x * blockDim.x + threadIdx.x;
  if (t < zero_n) zero_counts[t] = 0;
  if (t >= nt) return;
  tear::rebuildTriangle(s, t, accept, dir, rank, n);
}

// ----------------------------------------------------------------------------------------------
// Device-resident rebuild (host/tear/tearing_rebuild.h runs the same steps on the CPU as the reference).

// Corner h of the triangle list: key its particle, value its triangle (sorted: particle -> triangles).
__global__ void cornerKernel(const std::int32_t* tris, int nh, std::uint32_t* key, std::int32_t* tri) {
  const int h = blockIdx.x * blockDim.x + threadIdx.x;
  if (h >= nh) return;
  key[h] = std::uint32_t(tris[h]);
  tri[h] = h / 3;
}

__global__ void csrFromSorted32Kernel(int n, const std::uint32_t* sorted, int count, std::int32_t* offsets) {
  const int p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p > n) return;
  offsets[p] = std::int32_t(tear::lowerBound<std::uint32_t>(sorted, count, std::uint32_t(p)));
}

__global__ void halfEdgeKernel(const std::int32_t* tris, int nh, int bits, std::uint64_t* key, std::int32_t* opp) {
  const int h = blockIdx.x * blockDim.x + threadIdx.x;
  if (h >= nh) return;
  tear::halfEdge(tris, h, bits, key[h], opp[h]);
}

__global__ void runFlagsKernel(const std::uint64_t* key, int nh, std::int32_t* head, std::int32_t* bend) {
  const int h = blockIdx.x * blockDim.x + threadIdx.x;
  if (h >= nh) return;
  const bool hd = tear::runHead(key, h);
  head[h] = hd ? 1 : 0;
  bend[h] = hd && tear::runLength(key, h, nh) == 2 ? 1 : 0;
}

template <typename T>
__global__ void writeConstraintsKernel(const std::uint64_t* key, const std::int32_t* opp, const std::int32_t* head,
                                       const std::int32_t* e_idx, const std::int32_t* b_idx, int nh, int bits,
                                       const Vec3<T>* rest, T stretch_c, T bend_c, std::int32_t* edge_a,
                                       std::int32_t* edge_b, std::int32_t* d_ids, T* d_rest, T* d_comp,
                                       std::int32_t* b_ids, T* b_rest, T* b_comp) {
  const int h = blockIdx.x * blockDim.x + threadIdx.x;
  if (h >= nh || !head[h]) return;
  tear::writeEdgeConstraints<T>(key, opp, h, tear::runLength(key, h, nh), bits, e_idx[h], b_idx[h], rest, stretch_c,
                                bend_c, edge_a, edge_b, d_ids, d_rest, d_comp, b_ids, b_rest, b_comp);
}

// counts[0] = unique edges, counts[1] = bending constraints (inclusive ends of the exclusive scans).
__global__ void runCountsKernel(const std::int32_t* head, const std::int32_t* bend, const std::int32_t* e_idx,
                                const std::int32_t* b_idx, int nh, int* counts) {
  if (blockIdx.x != 0 || threadIdx.x != 0) return;
  counts[0] = nh > 0 ? e_idx[nh - 1] + head[nh - 1] : 0;
  counts[1] = nh > 0 ? b_idx[nh - 1] + bend[nh - 1] : 0;
}

// Both directions of edge e as (owner << bits | partner): sorted, the particle -> partners CSR.
__global__ void partnerKeysKernel(const std::int32_t* edge_a, const std::int32_t* edge_b, int ne, int bits,
                                  std::uint64_t* key) {
  const int e = blockIdx.x * blockDim.x + threadIdx.x;
  if (e >= ne) return;
  key[2 * e] = (std::uint64_t(edge_a[e]) << bits) | std::uint64_t(edge_b[e]);
  key[2 * e + 1] = (std::uint64_t(edge_b[e]) << bits) | std::uint64_t(edge_a[e]);
}

__global__ void partnerListKernel(const std::uint64_t* sorted, int count, int bits, std::int32_t* partner) {
  const int q = blockIdx.x * blockDim.x + threadIdx.x;
  if (q >= count) return;
  partner[q] = tear::edgeLow(sorted[q], bits);
}

__global__ void csrFromSorted64Kernel(int n, const std::uint64_t* sorted, int count, int bits, std::int32_t* offsets) {
  const int p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p > n) return;
  offsets[p] = std::int32_t(tear::lowerBound<std::uint64_t>(sorted, count, std::uint64_t(p) << bits));
}

// Per-particle rebuild (physics/tearing_rebuild.h; rebuildTearFans in host/tear/tearing_rebuild.h is its CPU
// reference). A particle -> items CSR from the items' particles key[0 .. m) (the corners' vertices, or the bending
// slots' particles): counts by integer atomics (exact, so deterministic), a scan, placement of item / per through
// atomic cursors (any order within a row: the triangle of a corner, per = 3; the slot itself, per = 1), then
// sortRowsKernel puts each row in the one ascending order. Neighbouring items often share a particle (a bending
// constraint's wing is the next one's upper end; neighbouring triangles share corners), so the lanes of a warp
// with the same particle make one atomic together (about half as many on the leg sheet's bending slots).
__device__ __forceinline__ unsigned keyPeers(unsigned lanes, std::int32_t key, int& leader, int& rank) {
  const unsigned peers = __match_any_sync(lanes, key);
  const int lane = int(threadIdx.x) & 31;
  leader = __ffs(int(peers)) - 1;
  rank = __popc(peers & ((1u << lane) - 1u));
  return peers;
}

// One item of particle p counted; lanes: the warp's lanes that count (each calls this once).
__device__ __forceinline__ void countRowItem(unsigned lanes, std::int32_t p, std::int32_t* count) {
  int leader = 0, rank = 0;
  const unsigned peers = keyPeers(lanes, p, leader, rank);
  if (rank == 0) atomicAdd(count + p, __popc(peers));
}

__global__ void rowCountKernel(const std::int32_t* key, int m, std::int32_t* count) {
  const int h = blockIdx.x * blockDim.x + threadIdx.x;
  const unsigned lanes = __ballot_sync(0xffffffffu, h < m);
  if (h < m) countRowItem(lanes, key[h], count);
}

__global__ void rowScatterKernel(const std::int32_t* key, int m, int per, const std::int32_t* off, std::int32_t* count,
                                 std::int32_t* rows) {
  const int h = blockIdx.x * blockDim.x + threadIdx.x;
  const unsigned lanes = __ballot_sync(0xffffffffu, h < m);
  if (h >= m) return;
  const std::int32_t p = key[h];
  int leader = 0, rank = 0;
  const unsigned peers = keyPeers(lanes, p, leader, rank);
  int top = 0;  // the row's free end before this group: its members take top - 1, top - 2, ...
  if (rank == 0) top = atomicSub(count + p, __popc(peers));
  top = __shfl_sync(peers, top, leader);
  rows[off[p] + top - rank - 1] = h / per;
}

// The block's rows are one contiguous range: loaded into shared memory with coalesced loads, sorted there per
// thread, stored back coalesced. Each thread reading its own row from global memory made every load and store
// instruction of a warp touch 32 different rows (ncu: the bending rows' sort was bound by L1 wavefronts, 27 us on
// the 150k sheet). A block whose rows exceed the staging (average over kStagedRow entries) sorts in place.
constexpr int kStagedRow = 16;
__global__ void __launch_bounds__(kBlock) sortRowsKernel(int n, const std::int32_t* off, std::int32_t* rows) {
  __shared__ std::int32_t stage[kBlock * kStagedRow];
  const int p0 = blockIdx.x * kBlock, p1 = min(p0 + kBlock, n);
  const std::int32_t b0 = off[p0], len = off[p1] - b0;
  const bool staged = len <= kBlock * kStagedRow;  // the same for every thread of the block
  if (staged) {
    for (int k = int(threadIdx.x); k < len; k += kBlock) stage[k] = rows[b0 + k];
    __syncthreads();
  }
  const int p = p0 + int(threadIdx.x);
  if (p < n) tear::sortRowLocal(staged ? stage + (off[p] - b0) : rows + off[p], off[p + 1] - off[p]);
  if (staged) {
    __syncthreads();
    for (int k = int(threadIdx.x); k < len; k += kBlock) rows[b0 + k] = stage[k];
  }
}

// n + 1 entries (entry n zero) so that the exclusive scan's entry n is the totals.
__global__ void fanCountsKernel(tear::Fan f, int n, tear::FanCounts* counts) {
  const int p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p > n) return;
  counts[p] = p < n ? tear::fanCounts(f, p) : tear::FanCounts();
}

// Per particle p <= n: offsets; p < n: writeFanEdges. A block's particles write contiguous ranges of the partner
// rows, the edges and the bending constraints, each thread a few entries of each: stored directly, every store
// instruction of a warp touched ~32 scattered sectors (the pass was bound by those writes, 56-58 us on the 150k
// sheet). So a block stages its ranges in shared memory and stores them coalesced; the constant compliances are
// filled in the same loops. A block whose ranges exceed the staging (a very large fan) writes directly.
// Blocks of 128 threads, nine per SM (<= 56 registers, 24 KB of staging each in float): the sheet's ~150k threads
// in one wave.
constexpr int kFanBlock = 128;
constexpr int kStagedPartners = 8 * kFanBlock, kStagedEdges = 4 * kFanBlock, kStagedBends = 4 * kFanBlock;
template <typename T>
__global__ void __launch_bounds__(kFanBlock, 9)
    fanEdgesKernel(tear::Fan f, tear::FanOutputs<T> o, int n, std::int32_t* zero_counts) {
  __shared__ std::int32_t s_partner[kStagedPartners], s_slot[kStagedPartners];
  __shared__ std::int32_t s_dist_ids[2 * kStagedEdges], s_bend_ids[4 * kStagedBends];
  __shared__ T s_dist_rest[kStagedEdges], s_bend_rest[kStagedBends];
  const int p0 = blockIdx.x * kFanBlock, p = p0 + int(threadIdx.x);
  if (p <= n) {
    tear::writeFanOffsets(o, p);
    if (zero_counts) zero_counts[p] = 0;  // the bending rows' counts, accumulated next (a memset fewer)
  }
  if (p0 >= n) return;  // the whole block: only the totals' offsets
  const int p1 = min(p0 + kFanBlock, n);
  const tear::FanCounts lo = o.off[p0], hi = o.off[p1];
  const int np = hi.partners - lo.partners, ne = hi.upper - lo.upper, nb = hi.bend_upper - lo.bend_upper;
  const bool staged = np <= kStagedPartners && ne <= kStagedEdges && nb <= kStagedBends;  // uniform in the block
  tear::FanOutputs<T> so = o;
  if (staged) {
    so.pe_partner = s_partner;
    so.dist_particle_slots = s_slot;
    so.partner_base = lo.partners;
    so.dist_ids = s_dist_ids;
    so.dist_rest = s_dist_rest;
    so.dist_compliance = nullptr;
    so.edge_base = lo.upper;
    so.bend_ids = o.bend_ids ? s_bend_ids : nullptr;
    so.bend_rest = s_bend_rest;
    so.bend_compliance = nullptr;
    so.bend_base = lo.bend_upper;
  }
  if (p < n) tear::writeFanEdges(f, so, p);
  if (!staged) return;
  __syncthreads();
  const int t = int(threadIdx.x);
  // The slots' lower parts (not written here) are written by lowerSlotsAndCountsKernel afterwards.
  for (int k = t; k < np; k += kFanBlock) {
    o.pe_partner[lo.partners + k] = s_partner[k];
    o.dist_particle_slots[lo.partners + k] = s_slot[k];
  }
  for (int k = t; k < 2 * ne; k += kFanBlock) o.dist_ids[2 * std::int64_t(lo.upper) + k] = s_dist_ids[k];
  for (int k = t; k < ne; k += kFanBlock) {
    o.dist_rest[lo.upper + k] = s_dist_rest[k];
    o.dist_compliance[lo.upper + k] = o.stretch_compliance;
  }
  if (!o.bend_ids) return;
  for (int k = t; k < 4 * nb; k += kFanBlock) o.bend_ids[4 * std::int64_t(lo.bend_upper) + k] = s_bend_ids[k];
  for (int k = t; k < nb; k += kFanBlock) {
    o.bend_rest[lo.bend_upper + k] = s_bend_rest[k];
    o.bend_compliance[lo.bend_upper + k] = o.bending_compliance;
  }
}

// After writeFanEdges, in one launch: thread e < ne writes edge e's lower distance slot (writeLowerDistanceSlot);
// thread ne + h, h < m, counts bending slot h for its particle key[h] (as rowCountKernel).
template <typename T>
__global__ void lowerSlotsAndCountsKernel(tear::FanOutputs<T> o, int ne, const std::int32_t* key, int m,
                                          std::int32_t* count) {
  const int g = blockIdx.x * blockDim.x + threadIdx.x, h = g - ne;
  const bool counting = h >= 0 && h < m;
  const unsigned lanes = __ballot_sync(0xffffffffu, counting);  // every lane of the warp reaches this
  if (g < ne) tear::writeLowerDistanceSlot(o, g);
  if (counting) countRowItem(lanes, key[h], count);
}

template <typename T>
class TearCudaWorkspace {
 public:
  TearStepStats step(TearSheet<T>& s, const TearParams<T>& p, TearCandidates<T>* out) {
    const std::size_t n = s.size(), nt = s.tris.size();
    TearStepStats st;
    if (n == 0) return st;
    // Particle arrays get room for one new particle per old one (the most a step can create), so that the
    // split kernel writes in place.
    reserveAndUpload(rest_, s.rest, 2 * n);
    reserveAndUpload(x_, s.x, 2 * n);
    reserveAndUpload(v_, s.v, 2 * n);
    reserveAndUpload(mass_, s.mass, 2 * n);
    reserveAndUpload(fixed_, s.fixed, 2 * n);
    reserveAndUpload(k_, s.k, 2 * n);
    reserveAndUpload(tau_, s.tau_f, 2 * n);
    tris_.upload(s.tris.empty() ? nullptr : s.tris.front().data(), 3 * nt);
    pe_off_.upload(s.pe_offsets);
    pe_partner_.upload(s.pe_partner);
    pt_off_.upload(s.pt_offsets);
    pt_tris_.upload(s.pt_tris);
    yield_.resize(n);
    accept_.resize(n);
    accept_i32_.resize(n);
    rank_.resize(n + 1);
    partner_.resize(n);
    dir_.resize(n);
    t_pred_.resize(n);
    ids_.resize(n);
    list_.resize(n);
    count_.resize(1);

    tear::SheetView<T> view;
    view.rest = rest_.data();
    view.x = x_.data();
    view.v = v_.data();
    view.mass = mass_.data();
    view.fixed = fixed_.data();
    view.k = k_.data();
    view.tau_f = tau_.data();
    view.tris = tris_.data();
    view.pe_offsets = pe_off_.data();
    view.pe_partner = pe_partner_.data();
    view.pt_offsets = pt_off_.data();
    view.pt_tris = pt_tris_.data();

    const int ni = int(n);
    detectKernel<T><<<gridFor(n), kBlock>>>(view, ni, int(p.criterion), p.break_strain, yield_.data(), partner_.data(),
                                            dir_.data(), t_pred_.data());
    INC_CUDA_LAUNCH("tear detect");
    acceptKernel<T>
        <<<gridFor(n), kBlock>>>(view, ni, yield_.data(), p.seed, s.step, accept_.data(), accept_i32_.data());
    INC_CUDA_LAUNCH("tear accept");
    // Prefix sum: rank[i] = accepted particles before i; rank[n] = their number (inclusive end via n + 1).
    std::size_t bytes = 0;
    INC_CUDA(cub::DeviceScan::ExclusiveSum(nullptr, bytes, accept_i32_.data(), rank_.data(), ni));
    std::size_t bytes2 = 0;
    INC_CUDA(cub::DeviceSelect::Flagged(nullptr, bytes2, ids_.data(), accept_.data(), list_.data(), count_.data(), ni));
    temp_.resize(std::max(bytes, bytes2));
    iotaKernel<<<gridFor(n), kBlock>>>(ids_.data(), ni);
    INC_CUDA_LAUNCH("tear iota");
    INC_CUDA(cub::DeviceScan::ExclusiveSum(temp_.data(), bytes, accept_i32_.data(), rank_.data(), ni));
    // Stream compaction: the accepted particle ids, ascending.
    INC_CUDA(
        cub::DeviceSelect::Flagged(temp_.data(), bytes2, ids_.data(), accept_.data(), list_.data(), count_.data(), ni));
    // One synchronisation: the number of new particles sizes the arrays and the split launch.
    int splits = 0;
    INC_CUDA(cudaMemcpy(&splits, count_.data(), sizeof(int), cudaMemcpyDeviceToHost));

    if (out) {
      out->yield = yield_.download();
      out->accept = accept_.download();
      out->partner = partner_.download();
      out->dir = dir_.download();
      out->t_pred = t_pred_.download();
    }
    {
      const std::vector<std::uint8_t> y = out ? out->yield : yield_.download();
      for (std::uint8_t f : y) st.yielding += f;
    }
    st.splits = splits;
    st.deferred = st.yielding - splits;
    if (splits == 0) {
      ++s.step;
      return st;
    }
    moved_.resize(std::size_t(splits));
    backed_.resize(std::size_t(splits));
    const bool debris = p.criterion != TearCriterion::Threshold;
    splitKernel<T><<<gridFor(std::size_t(splits)), kBlock>>>(
        view, list_.data(), splits, accept_.data(), rank_.data(), ni, partner_.data(), dir_.data(), t_pred_.data(),
        debris, p.random_range, p.t_lo, p.t_hi, p.min_area_ratio, p.seed, s.step, moved_.data(), backed_.data());
    INC_CUDA_LAUNCH("tear split");
    if (nt > 0) {
      triangleKernel<T><<<gridFor(nt), kBlock>>>(view, int(nt), accept_.data(), dir_.data(), rank_.data(), ni);
      INC_CUDA_LAUNCH("tear triangles");
    }
    const std::size_t m = n + std::size_t(splits);
    s.resizeParticles(m);
    rest_.download(s.rest.data(), m);
    x_.download(s.x.data(), m);
    v_.download(s.v.data(), m);
    mass_.download(s.mass.data(), m);
    fixed_.download(s.fixed.data(), m);
    k_.download(s.k.data(), m);
    tau_.download(s.tau_f.data(), m);
    if (nt > 0) tris_.download(s.tris.front().data(), 3 * nt);
    const std::vector<int> mv = moved_.download(), bk = backed_.download();
    for (int v : mv) st.moved_triangles += v;
    for (int v : bk) st.backed_off += v;
    ++s.step;
    return st;
  }

 private:
  template <typename U>
  static void reserveAndUpload(DeviceBuffer<U>& b, const std::vector<U>& host, std::size_t capacity) {
    b.resize(capacity);                  // grows only; never shrinks
    b.upload(host.data(), host.size());  // within capacity: no reallocation
  }

  DeviceBuffer<Vec3<T>> rest_, x_, v_, dir_;
  DeviceBuffer<T> mass_, k_, tau_, t_pred_;
  DeviceBuffer<std::uint8_t> fixed_, yield_, accept_;
  DeviceBuffer<std::int32_t> tris_, pe_off_, pe_partner_, pt_off_, pt_tris_, accept_i32_, rank_, partner_, ids_, list_;
  DeviceBuffer<int> count_, moved_, backed_;
  DeviceBuffer<unsigned char> temp_;
};

// The sheet kept on the device between frames (docs/tearing.md, "GPU pipeline"): positions, velocities,
// rest positions and masses are the PBD backend's arrays; this owns the rest (fixed, k, tau_f, triangles,
// adjacency) and, after a step with splits, appends the new particles to the PBD model and rewrites its
// distance and bending blocks on the device (per particle by default, by radix sorts with
// TearModelOptions::device_sorted_rebuild). All kernels run on the legacy default stream, which orders
// itself with the PBD backend's (blocking) stream. Host synchronisations per tearing step: the split and
// yield counts (sizes the split launch and the particle append), the constraint counts after the rebuild
// (size the PBD blocks' launches), and a reallocation when the particle capacity is exceeded.
template <typename T>
class TearResident {
 public:
  bool attach(PbdBackend<T>& pbd, const TearSheet<T>& s, const TearModelOptions& opt, int model_blocks) {
    patch_ = pbdDevicePatch<T>(pbd);
    if (!patch_ || model_blocks < 1 || model_blocks > 2) return false;
    opt_ = opt;
    sorted_ = opt.device_sorted_rebuild;
    bending_ = model_blocks == 2;
    n_ = int(s.size());
    nt_ = int(s.tris.size());
    // Room for growth: a quarter more particles before the first reallocation.
    const std::size_t cap = std::size_t(n_) + std::max<std::size_t>(1024, std::size_t(n_) / 4);
    patch_->reserveParticles(cap);
    fixed_.resize(cap);
    k_.resize(cap);
    tau_.resize(cap);
    fixed_.upload(s.fixed);  // within capacity: no reallocation
    k_.upload(s.k);
    tau_.upload(s.tau_f);
    tris_.upload(s.tris.empty() ? nullptr : s.tris.front().data(), 3 * std::size_t(nt_));
    pe_off_.upload(s.pe_offsets);
    pe_partner_.upload(s.pe_partner);
    pt_off_.upload(s.pt_offsets);
    pt_tris_.upload(s.pt_tris);
    // The triangle count never changes in a tearing step: unique edges <= 3 nt, interior edges <= 3 nt / 2.
    const std::size_t nh = 3 * std::size_t(nt_);
    patch_->reserveBlock(0, std::max<std::size_t>(nh, 1));
    if (bending_) patch_->reserveBlock(1, std::max<std::size_t>(nh / 2, 1));
    counts_.resize(2);
    INC_CUDA(cudaDeviceSynchronize());
    return true;
  }

  std::size_t size() const { return std::size_t(n_); }

  int step(const TearParams<T>& p, std::uint32_t step, TearFrameStats& st, bool profile) {
    using Clock = std::chrono::steady_clock;
    auto t0 = Clock::now();
    auto stage = [&](const char* name) {
      if (profile) INC_CUDA(cudaDeviceSynchronize());
      const auto t1 = Clock::now();
      const double ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
      st.stages.push_back({name, ms});
      t0 = t1;
      return ms;
    };
    const int n = n_;
    if (n == 0) return 0;
    const std::size_t nz = std::size_t(n);
    yield_.resize(nz);
    yield_accept_.resize(nz);
    accept_.resize(nz);
    accept_i32_.resize(nz);
    rank_.resize(nz + 1);
    partner_.resize(nz);
    dir_.resize(nz);
    t_pred_.resize(nz);
    ensureTemp();
    tear::SheetView<T> view = sheetView();
    detectKernel<T><<<gridFor(nz), kBlock>>>(view, n, int(p.criterion), p.break_strain, yield_.data(), partner_.data(),
                                             dir_.data(), t_pred_.data());
    INC_CUDA_LAUNCH("tear detect");
    acceptKernel<T><<<gridFor(nz), kBlock>>>(view, n, yield_.data(), p.seed, step, accept_.data(), accept_i32_.data(),
                                             yield_accept_.data());
    INC_CUDA_LAUNCH("tear accept");
    // Synchronisation 1: the yield and split counts (one reduction); the split count sizes the split launch and
    // the particle append. A frame without splits (most frames) stops here.
    std::size_t bytes = temp_.capacity();
    INC_CUDA(cub::DeviceReduce::Reduce(temp_.data(), bytes, yield_accept_.data(), yield_accept_sum_.data(), n,
                                       AddInt2(), make_int2(0, 0)));
    int2 cnt = make_int2(0, 0);
    staging_.download(&cnt, yield_accept_sum_.data(), 1, cudaStreamLegacy);
    const int splits = cnt.y;
    st.splits += splits;
    st.yielding += cnt.x;
    st.deferred += cnt.x - splits;
    stage("tear_detect");
    if (splits == 0) return 0;
    // rank[i] = accepted particles before i: the new particle's index offset.
    bytes = temp_.capacity();
    INC_CUDA(cub::DeviceScan::ExclusiveSum(temp_.data(), bytes, accept_i32_.data(), rank_.data(), n));

    const int m = n + splits;
    patch_->reserveParticles(std::size_t(m));  // reallocates (and synchronises) only beyond the capacity
    growKeep(fixed_, std::size_t(m), nz);
    growKeep(k_, std::size_t(m), nz);
    growKeep(tau_, std::size_t(m), nz);
    fixed_.resize(std::size_t(m));
    k_.resize(std::size_t(m));
    tau_.resize(std::size_t(m));
    view = sheetView();  // pointers may have moved
    const bool debris = p.criterion != TearCriterion::Threshold;
    // Over all particles: no compaction of the accepted ones (a selection's dispatch cost more host time than
    // the threads that return at once).
    splitKernel<T><<<gridFor(nz), kBlock>>>(view, nullptr, n, accept_.data(), rank_.data(), n, partner_.data(),
                                            dir_.data(), t_pred_.data(), debris, p.random_range, p.t_lo, p.t_hi,
                                            p.min_area_ratio, p.seed, step, nullptr, nullptr);
    INC_CUDA_LAUNCH("tear split");
    // The triangles, and the first rebuild pass's counts cleared (m + 1 entries: the per-particle rebuild).
    const int zero_n = sorted_ ? 0 : m + 1;
    pt_count_.resize(std::size_t(m) + 1);
    if (std::max(nt_, zero_n) > 0) {
      triangleKernel<T><<<gridFor(std::size_t(std::max(nt_, zero_n))), kBlock>>>(
          view, nt_, accept_.data(), dir_.data(), rank_.data(), n, pt_count_.data(), zero_n);
      INC_CUDA_LAUNCH("tear triangles");
    }
    stage("tear_split");
    const auto r0 = Clock::now();
    patch_->appendParticles(m, fixed_.data());  // new particles, inverse masses of the split ones
    n_ = m;
    stage("append_particles");
    rebuild(stage);
    st.rebuild_ms += std::chrono::duration<double, std::milli>(Clock::now() - r0).count();
    return splits;
  }

  void download(TearSheet<T>& s, bool full) {
    INC_CUDA(cudaDeviceSynchronize());
    const PbdDeviceParticles<T> d = patch_->deviceParticles();
    const std::size_t m = std::size_t(n_);
    if (!full && s.size() == m) {
      if (m) {
        INC_CUDA(cudaMemcpy(s.x.data(), d.x, m * sizeof(Vec3<T>), cudaMemcpyDeviceToHost));
        INC_CUDA(cudaMemcpy(s.v.data(), d.v, m * sizeof(Vec3<T>), cudaMemcpyDeviceToHost));
      }
      return;
    }
    s.resizeParticles(m);
    if (m) {
      INC_CUDA(cudaMemcpy(s.rest.data(), d.rest, m * sizeof(Vec3<T>), cudaMemcpyDeviceToHost));
      INC_CUDA(cudaMemcpy(s.x.data(), d.x, m * sizeof(Vec3<T>), cudaMemcpyDeviceToHost));
      INC_CUDA(cudaMemcpy(s.v.data(), d.v, m * sizeof(Vec3<T>), cudaMemcpyDeviceToHost));
      INC_CUDA(cudaMemcpy(s.mass.data(), d.mass, m * sizeof(T), cudaMemcpyDeviceToHost));
      fixed_.download(s.fixed.data(), m);
      k_.download(s.k.data(), m);
      tau_.download(s.tau_f.data(), m);
    }
    s.tris.resize(std::size_t(nt_));
    if (nt_ > 0) tris_.download(s.tris.front().data(), 3 * std::size_t(nt_));
  }

 private:
  // CUB's scratch for every scan and reduction of a step, sized once for the particle capacity (each
  // algorithm's need grows with the item count, so the capacity's covers every smaller call): a size query is a
  // host-side dispatch as costly as the call itself, and a step made ten of them.
  void ensureTemp() {
    const std::size_t cap = std::max<std::size_t>(patch_->deviceParticles().capacity, std::size_t(n_)) + 1;
    if (cap <= temp_items_) return;
    const int c = int(cap);
    std::size_t b[4] = {0, 0, 0, 0};
    yield_accept_sum_.resize(1);
    INC_CUDA(cub::DeviceReduce::Reduce(nullptr, b[0], yield_accept_.data(), yield_accept_sum_.data(), c, AddInt2(),
                                       make_int2(0, 0)));
    INC_CUDA(cub::DeviceScan::ExclusiveSum(nullptr, b[1], accept_i32_.data(), rank_.data(), c));
    INC_CUDA(cub::DeviceScan::ExclusiveScan(nullptr, b[2], fan_counts_.data(), fan_off_.data(), tear::AddFanCounts(),
                                            tear::FanCounts(), c));
    INC_CUDA(cub::DeviceScan::ExclusiveSum(nullptr, b[3], pt_count_.data(), pt_off_.data(), c));
    temp_.resize(std::max<std::size_t>(*std::max_element(b, b + 4), 1));
    temp_items_ = cap;
  }

  tear::SheetView<T> sheetView() {
    const PbdDeviceParticles<T> d = patch_->deviceParticles();
    tear::SheetView<T> v;
    v.rest = d.rest;
    v.x = d.x;
    v.v = d.v;
    v.mass = d.mass;
    v.fixed = fixed_.data();
    v.k = k_.data();
    v.tau_f = tau_.data();
    v.tris = tris_.data();
    v.pe_offsets = pe_off_.data();
    v.pe_partner = pe_partner_.data();
    v.pt_offsets = pt_off_.data();
    v.pt_tris = pt_tris_.data();
    return v;
  }

  template <typename Stage>
  void rebuild(Stage& stage) {
    if (sorted_)
      rebuildSorted(stage);
    else
      rebuildFans(stage);
  }

  // The adjacency and the PBD blocks from the device triangles, per particle (rebuildTearFans in
  // host/tear/tearing_rebuild.h, steps 1-5; step 5 is commitBlockIncidence).
  template <typename Stage>
  void rebuildFans(Stage& stage) {
    const int n = n_, nh = 3 * nt_;
    const std::size_t nz = std::size_t(n), nhz = std::size_t(std::max(nh, 1));
    // 1: particle -> triangles: counts, exclusive scan over n + 1 (entry n = nh), scatter, rows sorted.
    pt_count_.resize(nz + 1);  // cleared by the step's triangle kernel
    pt_off_.resize(nz + 1);
    pt_tris_.resize(std::size_t(nh));
    if (nh > 0) {
      rowCountKernel<<<gridFor(nhz), kBlock>>>(tris_.data(), nh, pt_count_.data());
      INC_CUDA_LAUNCH("tear corner counts");
    }
    fan_counts_.resize(nz + 1);
    fan_off_.resize(nz + 1);
    ensureTemp();  // sized for the particle capacity, which appendParticles kept above n
    std::size_t b1 = temp_.capacity(), b2 = temp_.capacity();
    INC_CUDA(cub::DeviceScan::ExclusiveSum(temp_.data(), b1, pt_count_.data(), pt_off_.data(), n + 1));
    if (nh > 0) {
      rowScatterKernel<<<gridFor(nhz), kBlock>>>(tris_.data(), nh, 3, pt_off_.data(), pt_count_.data(),
                                                 pt_tris_.data());
      INC_CUDA_LAUNCH("tear corner scatter");
    }
    if (n > 0) {
      sortRowsKernel<<<gridFor(nz), kBlock>>>(n, pt_off_.data(), pt_tris_.data());
      INC_CUDA_LAUNCH("tear particle triangles");
    }
    // 2: per-particle counts and their exclusive scan (entry n: the totals).
    tear::Fan fan;
    fan.tris = tris_.data();
    fan.pt_offsets = pt_off_.data();
    fan.pt_tris = pt_tris_.data();
    fanCountsKernel<<<gridFor(nz + 1), kBlock>>>(fan, n, fan_counts_.data());
    INC_CUDA_LAUNCH("tear fan counts");
    INC_CUDA(cub::DeviceScan::ExclusiveScan(temp_.data(), b2, fan_counts_.data(), fan_off_.data(), tear::AddFanCounts(),
                                            tear::FanCounts(), n + 1));
    // Room for the constraints before the counts are known: unique edges <= nh, interior edges <= nh / 2.
    const PbdDeviceBlock<T> dist = patch_->reserveBlock(0, nhz);
    PbdDeviceBlock<T> bend;
    if (bending_) bend = patch_->reserveBlock(1, std::max<std::size_t>(nhz / 2, 1));
    // Synchronisation 2: the totals size the partner list and the PBD blocks' launches.
    tear::FanCounts total;
    staging_.download(&total, fan_off_.data() + n, 1, cudaStreamLegacy);
    const int ne = total.upper, nb = total.bend_upper;
    if (total.partners != 2 * ne)
      throw InputError("tearing", "topology",
                       "device rebuild: inconsistent counts (a degenerate or duplicated triangle)");
    stage("rebuild_edges");
    // 3: partner rows, edges as constraints, the distance rows' upper parts, CSR offsets.
    pe_off_.resize(nz + 1);
    pe_partner_.resize(std::size_t(2 * ne));
    const PbdDeviceIncidence inc_d = patch_->reserveIncidence(0, std::size_t(ne));
    PbdDeviceIncidence inc_b;
    if (bending_) inc_b = patch_->reserveIncidence(1, std::size_t(nb));
    const PbdDeviceParticles<T> d = patch_->deviceParticles();
    tear::FanOutputs<T> o;
    o.off = fan_off_.data();
    o.rest = d.rest;
    o.stretch_compliance = T(opt_.stretch_compliance);
    o.bending_compliance = T(opt_.bending_compliance);
    o.pe_offsets = pe_off_.data();
    o.pe_partner = pe_partner_.data();
    o.dist_ids = dist.ids;
    o.dist_rest = dist.rest;
    o.dist_compliance = dist.compliance;
    o.dist_particle_offsets = inc_d.particle_offsets;
    o.dist_particle_slots = inc_d.particle_slots;
    if (bending_) {
      o.bend_ids = bend.ids;
      o.bend_rest = bend.rest;
      o.bend_compliance = bend.compliance;
      o.bend_particle_offsets = inc_b.particle_offsets;
      o.bend_particle_slots = inc_b.particle_slots;
    }
    if (bending_) bend_count_.resize(nz + 1);
    fanEdgesKernel<T><<<unsigned((nz + 1 + kFanBlock - 1) / kFanBlock), kFanBlock>>>(
        fan, o, n, bending_ ? bend_count_.data() : nullptr);
    INC_CUDA_LAUNCH("tear fan edges");
    stage("rebuild_adjacency");
    // 4: the rest of the distance rows (per edge) and the bending rows (from the bending constraints, as the
    // corners' rows); 5: offsets, Jacobi scales, multipliers.
    // The bending rows' counts were cleared by fanEdgesKernel; the lower distance slots and the slot counts in one
    // launch.
    const int bs = bending_ ? 4 * nb : 0;
    if (ne + bs > 0) {
      lowerSlotsAndCountsKernel<T>
          <<<gridFor(std::size_t(ne) + std::size_t(bs)), kBlock>>>(o, ne, bend.ids, bs, bend_count_.data());
      INC_CUDA_LAUNCH("tear lower distance slots and bending slot counts");
    }
    if (bending_) {
      // The same n + 1 int scan as step 1's.
      b1 = temp_.capacity();
      INC_CUDA(cub::DeviceScan::ExclusiveSum(temp_.data(), b1, bend_count_.data(), inc_b.particle_offsets, n + 1));
      if (bs > 0) {
        rowScatterKernel<<<gridFor(std::size_t(bs)), kBlock>>>(bend.ids, bs, 1, inc_b.particle_offsets,
                                                               bend_count_.data(), inc_b.particle_slots);
        INC_CUDA_LAUNCH("tear bending slot rows");
      }
      if (n > 0) {
        sortRowsKernel<<<gridFor(nz), kBlock>>>(n, inc_b.particle_offsets, inc_b.particle_slots);
        INC_CUDA_LAUNCH("tear bending rows sorted");
      }
    }
    patch_->commitBlockIncidence(0, ne);
    if (bending_) patch_->commitBlockIncidence(1, nb);
    stage("rebuild_constraints");
  }

  // The older path (TearModelOptions::device_sorted_rebuild): the adjacency and the PBD blocks from the device
  // triangles by radix sorts (rebuildTearSorted in host/tear/tearing_rebuild.h, steps 1-4).
  template <typename Stage>
  void rebuildSorted(Stage& stage) {
    const int n = n_, nh = 3 * nt_;
    const int bits = tear::indexBits(n);
    const std::size_t nhz = std::size_t(std::max(nh, 1));
    // 1: particle -> triangles (stable radix sort of the corners by particle).
    c_key_.resize(nhz);
    c_key_out_.resize(nhz);
    c_tri_.resize(nhz);
    pt_tris_.resize(std::size_t(nh));
    pt_off_.resize(std::size_t(n) + 1);
    if (nh > 0) {
      cornerKernel<<<gridFor(nhz), kBlock>>>(tris_.data(), nh, c_key_.data(), c_tri_.data());
      INC_CUDA_LAUNCH("tear corners");
      std::size_t bytes = 0;
      INC_CUDA(cub::DeviceRadixSort::SortPairs(nullptr, bytes, c_key_.data(), c_key_out_.data(), c_tri_.data(),
                                               pt_tris_.data(), nh, 0, bits));
      temp_.resize(std::max<std::size_t>(bytes, 1));
      INC_CUDA(cub::DeviceRadixSort::SortPairs(temp_.data(), bytes, c_key_.data(), c_key_out_.data(), c_tri_.data(),
                                               pt_tris_.data(), nh, 0, bits));
    }
    csrFromSorted32Kernel<<<gridFor(std::size_t(n) + 1), kBlock>>>(n, c_key_out_.data(), nh, pt_off_.data());
    INC_CUDA_LAUNCH("tear particle triangles");
    // 2: half-edges sorted by (min, max) -> unique edges, bending on runs of two, numbered by prefix sums.
    h_key_.resize(nhz);
    h_key_out_.resize(nhz);
    h_opp_.resize(nhz);
    h_opp_out_.resize(nhz);
    head_.resize(nhz);
    bend_.resize(nhz);
    e_idx_.resize(nhz);
    b_idx_.resize(nhz);
    edge_a_.resize(nhz);
    edge_b_.resize(nhz);
    const PbdDeviceBlock<T> dist = patch_->reserveBlock(0, nhz);
    PbdDeviceBlock<T> bend;
    if (bending_) bend = patch_->reserveBlock(1, std::max<std::size_t>(nhz / 2, 1));
    if (nh > 0) {
      halfEdgeKernel<<<gridFor(nhz), kBlock>>>(tris_.data(), nh, bits, h_key_.data(), h_opp_.data());
      INC_CUDA_LAUNCH("tear half-edges");
      std::size_t bytes = 0, bs1 = 0, bs2 = 0;
      INC_CUDA(cub::DeviceRadixSort::SortPairs(nullptr, bytes, h_key_.data(), h_key_out_.data(), h_opp_.data(),
                                               h_opp_out_.data(), nh, 0, 2 * bits));
      INC_CUDA(cub::DeviceScan::ExclusiveSum(nullptr, bs1, head_.data(), e_idx_.data(), nh));
      INC_CUDA(cub::DeviceScan::ExclusiveSum(nullptr, bs2, bend_.data(), b_idx_.data(), nh));
      temp_.resize(std::max({bytes, bs1, bs2, std::size_t(1)}));
      INC_CUDA(cub::DeviceRadixSort::SortPairs(temp_.data(), bytes, h_key_.data(), h_key_out_.data(), h_opp_.data(),
                                               h_opp_out_.data(), nh, 0, 2 * bits));
      runFlagsKernel<<<gridFor(nhz), kBlock>>>(h_key_out_.data(), nh, head_.data(), bend_.data());
      INC_CUDA_LAUNCH("tear edge runs");
      INC_CUDA(cub::DeviceScan::ExclusiveSum(temp_.data(), bs1, head_.data(), e_idx_.data(), nh));
      INC_CUDA(cub::DeviceScan::ExclusiveSum(temp_.data(), bs2, bend_.data(), b_idx_.data(), nh));
      const PbdDeviceParticles<T> d = patch_->deviceParticles();
      writeConstraintsKernel<T><<<gridFor(nhz), kBlock>>>(
          h_key_out_.data(), h_opp_out_.data(), head_.data(), e_idx_.data(), b_idx_.data(), nh, bits, d.rest,
          T(opt_.stretch_compliance), T(opt_.bending_compliance), edge_a_.data(), edge_b_.data(), dist.ids, dist.rest,
          dist.compliance, bending_ ? bend.ids : nullptr, bend.rest, bend.compliance);
      INC_CUDA_LAUNCH("tear write constraints");
      runCountsKernel<<<1, 1>>>(head_.data(), bend_.data(), e_idx_.data(), b_idx_.data(), nh, counts_.data());
      INC_CUDA_LAUNCH("tear constraint counts");
    } else {
      INC_CUDA(cudaMemset(counts_.data(), 0, 2 * sizeof(int)));
    }
    // Synchronisation 2: the constraint counts size the PBD blocks' launches.
    int cnt[2] = {0, 0};
    INC_CUDA(cudaMemcpy(cnt, counts_.data(), sizeof(cnt), cudaMemcpyDeviceToHost));
    const int ne = cnt[0], nb = cnt[1];
    stage("rebuild_edges");
    // 3: particle -> partners (both directions of each edge sorted by (owner, partner)).
    const std::size_t np = std::size_t(2 * ne);
    p_key_.resize(std::max<std::size_t>(np, 1));
    p_key_out_.resize(std::max<std::size_t>(np, 1));
    pe_partner_.resize(np);
    pe_off_.resize(std::size_t(n) + 1);
    if (ne > 0) {
      partnerKeysKernel<<<gridFor(std::size_t(ne)), kBlock>>>(edge_a_.data(), edge_b_.data(), ne, bits, p_key_.data());
      INC_CUDA_LAUNCH("tear partner keys");
      std::size_t bytes = 0;
      INC_CUDA(cub::DeviceRadixSort::SortKeys(nullptr, bytes, p_key_.data(), p_key_out_.data(), int(np), 0, 2 * bits));
      temp_.resize(std::max<std::size_t>(bytes, 1));
      INC_CUDA(
          cub::DeviceRadixSort::SortKeys(temp_.data(), bytes, p_key_.data(), p_key_out_.data(), int(np), 0, 2 * bits));
      partnerListKernel<<<gridFor(np), kBlock>>>(p_key_out_.data(), int(np), bits, pe_partner_.data());
      INC_CUDA_LAUNCH("tear partners");
    }
    csrFromSorted64Kernel<<<gridFor(std::size_t(n) + 1), kBlock>>>(n, p_key_out_.data(), int(np), bits, pe_off_.data());
    INC_CUDA_LAUNCH("tear partner offsets");
    stage("rebuild_adjacency");
    // 4: the PBD blocks' incidence and Jacobi scales (radix sort inside the backend).
    patch_->commitBlock(0, ne);
    if (bending_) patch_->commitBlock(1, nb);
    stage("rebuild_constraints");
  }

  PbdDevicePatch<T>* patch_ = nullptr;
  TearModelOptions opt_;
  bool bending_ = false;
  bool sorted_ = false;  // the radix-sort rebuild instead of the per-particle one
  int n_ = 0, nt_ = 0;
  DeviceBuffer<std::uint8_t> fixed_, yield_, accept_;
  DeviceBuffer<T> k_, tau_, t_pred_;
  DeviceBuffer<Vec3<T>> dir_;
  DeviceBuffer<std::int32_t> tris_, pe_off_, pe_partner_, pt_off_, pt_tris_, accept_i32_, rank_, partner_, c_tri_,
      h_opp_, h_opp_out_, head_, bend_, e_idx_, b_idx_, edge_a_, edge_b_, pt_count_;
  DeviceBuffer<tear::FanCounts> fan_counts_, fan_off_;
  DeviceBuffer<std::int32_t> bend_count_;
  DeviceBuffer<std::uint32_t> c_key_, c_key_out_;
  DeviceBuffer<std::uint64_t> h_key_, h_key_out_, p_key_, p_key_out_;
  DeviceBuffer<int> counts_;
  DeviceBuffer<unsigned char> temp_;
  DeviceBuffer<int2> yield_accept_, yield_accept_sum_;
  std::size_t temp_items_ = 0;  // the item count temp_ was sized for (ensureTemp)
  PinnedStaging staging_;       // the two count read-backs of a tearing step
};

template <typename T>
class TearStepCuda final : public TearStepBackend<T> {
 public:
  BackendKind kind() const override { return BackendKind::Cuda; }
  int step(TearSheet<T>& s, const TearParams<T>& p, TearFrameStats& st) override {
    resident_ok_ = false;  // the host path owns the sheet now
    const TearStepStats r = ws_.step(s, p, nullptr);
    st.splits += r.splits;
    st.yielding += r.yielding;
    st.deferred += r.deferred;
    return r.splits;
  }
  bool attach(PbdBackend<T>& pbd, const TearSheet<T>& s, const TearModelOptions& opt, int model_blocks) override {
    resident_ok_ = res_.attach(pbd, s, opt, model_blocks);
    return resident_ok_;
  }
  int stepResident(const TearParams<T>& p, std::uint32_t step, TearFrameStats& st, bool profile) override {
    if (!resident_ok_) throw InputError("tearing", "device", "stepResident without a successful attach");
    return res_.step(p, step, st, profile);
  }
  std::size_t residentSize() const override { return resident_ok_ ? res_.size() : 0; }
  void download(TearSheet<T>& s, bool full) override {
    if (resident_ok_) res_.download(s, full);
  }

 private:
  TearCudaWorkspace<T> ws_;
  TearResident<T> res_;
  bool resident_ok_ = false;
};

}  // namespace

template <typename T>
std::unique_ptr<TearStepBackend<T>> makeTearStepCuda() {
  return std::make_unique<TearStepCuda<T>>();
}

template <typename T>
TearStepStats tearStepCuda(TearSheet<T>& s, const TearParams<T>& p, TearCandidates<T>* out) {
  TearCudaWorkspace<T> ws;
  return ws.step(s, p, out);
}

template std::unique_ptr<TearStepBackend<float>> makeTearStepCuda<float>();
template std::unique_ptr<TearStepBackend<double>> makeTearStepCuda<double>();
template TearStepStats tearStepCuda<float>(TearSheet<float>&, const TearParams<float>&, TearCandidates<float>*);
template TearStepStats tearStepCuda<double>(TearSheet<double>&, const TearParams<double>&, TearCandidates<double>*);

}  // namespace inc::cuda
