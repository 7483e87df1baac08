// CUDA tearing step: the physics/tearing_phases.h bodies as kernels, CUB exclusive sum and DeviceSelect for the split list.
#include "kernels/tearing_cuda.h"

#include <cub/cub.cuh>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "kernels/cuda_check.h"
#include "kernels/device_buffer.h"
#include "physics/tearing_phases.h"

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

template <typename T>
__global__ void acceptKernel(tear::SheetView<T> s, int n, const std::uint8_t* yield, std::uint32_t seed,
                             std::uint32_t step, std::uint8_t* accept, std::int32_t* accept_i32) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const std::uint8_t a = tear::acceptSplit(s, yield, i, seed, step);
  accept[i] = a;
  accept_i32[i] = a;
}

__global__ void iotaKernel(std::int32_t* out, int n) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) out[i] = i;
}

// Over the compacted list of accepted particles only.
template <typename T>
__global__ void splitKernel(tear::SheetView<T> s, const std::int32_t* list, int count, const std::int32_t* rank, int n,
                            const std::int32_t* partner, const Vec3<T>* dir, const T* t_pred, bool debris, T range,
                            T t_lo, T t_hi, T min_ratio, std::uint32_t seed, std::uint32_t step, int* moved,
                            int* backed) {
  const int k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= count) return;
  const std::int32_t i = list[k];
  const tear::SplitResult r = tear::splitParticle(s, i, std::size_t(n) + std::size_t(rank[i]), partner[i], dir[i],
                                                  t_pred[i], debris, range, t_lo, t_hi, min_ratio, seed, step);
  moved[k] = r.moved_triangles;
  backed[k] = r.backed_off;
}

template <typename T>
__global__ void triangleKernel(tear::SheetView<T> s, int nt, const std::uint8_t* accept, const Vec3<T>* dir,
                               const std::int32_t* rank, int n) {
  const int t = blockIdx.x * blockDim.x + threadIdx.x;
  if (t >= nt) return;
  tear::rebuildTriangle(s, t, accept, dir, rank, n);
}

template <typename T>
class TearCudaWorkspace {
 public:
  cpu::TearStepStats step(TearSheet<T>& s, const TearParams<T>& p, cpu::TearCandidates<T>* out) {
    const std::size_t n = s.size(), nt = s.tris.size();
    cpu::TearStepStats st;
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
    acceptKernel<T><<<gridFor(n), kBlock>>>(view, ni, yield_.data(), p.seed, s.step, accept_.data(), accept_i32_.data());
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
    INC_CUDA(cub::DeviceSelect::Flagged(temp_.data(), bytes2, ids_.data(), accept_.data(), list_.data(), count_.data(), ni));
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
    splitKernel<T><<<gridFor(std::size_t(splits)), kBlock>>>(view, list_.data(), splits, rank_.data(), ni,
                                                              partner_.data(), dir_.data(), t_pred_.data(), debris,
                                                              p.random_range, p.t_lo, p.t_hi, p.min_area_ratio, p.seed,
                                                              s.step, moved_.data(), backed_.data());
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
    b.resize(capacity);             // grows only; never shrinks
    b.upload(host.data(), host.size());  // within capacity: no reallocation
  }

  DeviceBuffer<Vec3<T>> rest_, x_, v_, dir_;
  DeviceBuffer<T> mass_, k_, tau_, t_pred_;
  DeviceBuffer<std::uint8_t> fixed_, yield_, accept_;
  DeviceBuffer<std::int32_t> tris_, pe_off_, pe_partner_, pt_off_, pt_tris_, accept_i32_, rank_, partner_, ids_, list_;
  DeviceBuffer<int> count_, moved_, backed_;
  DeviceBuffer<unsigned char> temp_;
};

template <typename T>
class TearStepCuda final : public TearStepBackend<T> {
 public:
  BackendKind kind() const override { return BackendKind::Cuda; }
  int step(TearSheet<T>& s, const TearParams<T>& p, TearFrameStats& st) override {
    const cpu::TearStepStats r = ws_.step(s, p, nullptr);
    st.splits += r.splits;
    st.yielding += r.yielding;
    st.deferred += r.deferred;
    return r.splits;
  }

 private:
  TearCudaWorkspace<T> ws_;
};

}  // namespace

template <typename T>
std::unique_ptr<TearStepBackend<T>> makeTearStepCuda() {
  return std::make_unique<TearStepCuda<T>>();
}

template <typename T>
cpu::TearStepStats tearStepCuda(TearSheet<T>& s, const TearParams<T>& p, cpu::TearCandidates<T>* out) {
  TearCudaWorkspace<T> ws;
  return ws.step(s, p, out);
}

template std::unique_ptr<TearStepBackend<float>> makeTearStepCuda<float>();
template std::unique_ptr<TearStepBackend<double>> makeTearStepCuda<double>();
template cpu::TearStepStats tearStepCuda<float>(TearSheet<float>&, const TearParams<float>&, cpu::TearCandidates<float>*);
template cpu::TearStepStats tearStepCuda<double>(TearSheet<double>&, const TearParams<double>&, cpu::TearCandidates<double>*);

}  // namespace inc::cuda
