// CUDA MLS solver: a team of lanes (small models) or one thread per particle per pass, fixed-shape block
// reductions for the frame metrics, the substeps of a frame as one persistent cooperative launch (or one CUDA
// graph) when stages are not timed.
#include "kernels/mls_solver_cuda.h"

#include <cooperative_groups.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "kernels/bulk_upload.h"
#include "kernels/cuda_check.h"
#include "kernels/device_buffer.h"
#include "kernels/graph_capture.h"
#include "kernels/pinned_staging.h"
#include "physics/cut_coupling.h"
#include "physics/mls_passes.h"

namespace inc::cuda {

namespace {

constexpr int kBlock = 256;
// Reduction: a fixed grid of kReduceBlocks blocks, each a fixed shared-memory tree over a grid-stride
// range, then the partials summed on the host in block order: deterministic run to run, no atomics.
constexpr int kReduceBlocks = 256;

int gridFor(std::int64_t n) { return int((n + kBlock - 1) / kBlock); }

template <typename T>
__global__ void driftKernel(MlsView<T> s, T dt, int remaining) {
  const std::int64_t k = std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (k < s.n) mlsDriftPass(s, k, dt, remaining);
}

// Lane teams: each particle (or coupling group) is served by L consecutive lanes of one warp, lane l adding the
// slots l, l + L, ... of its list (the physics headers' *PairSum / couplingMemberSum with first = l, stride = L),
// the team's partial sums added by xor shuffles, lane 0 finishing the particle. A cut's few thousand points are
// latency-bound (one thread walking ~50 neighbours is ~50 dependent loads); L = 1 is the plain one-thread loop,
// used for large models where the lanes would only multiply the threads (lanesFor).
template <int L, typename T>
__device__ void teamSum(T& v) {
  for (int o = L / 2; o > 0; o /= 2) v += __shfl_xor_sync(0xffffffffu, v, o);
}
template <int L, typename T>
__device__ void teamSum(Vec3<T>& v) {
  for (int c = 0; c < 3; ++c) teamSum<L>(v[c]);
}
template <int L, typename T>
__device__ void teamSum(Mat3<T>& m) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) teamSum<L>(m.m[r][c]);
}

// The displacement gradient of the team's particle i (every lane of the team gets it; no early exit before the
// shuffles: lanes past the end add zeros).
template <int L, typename T>
__device__ Mat3<T> teamGradient(const MlsView<T>& s, std::int64_t i, int lane) {
  Mat3<T> b;
  if (i < s.n) b = mlsGradientPairSum(s, i, lane, L);
  teamSum<L>(b);
  return i < s.n ? b * s.moment_inverse[i] : b;
}
template <int L, typename T>
__device__ Vec3<T> teamForce(const MlsView<T>& s, std::int64_t k, int lane) {
  Vec3<T> f;
  if (k < s.n) f = mlsForcePairSum(s, k, lane, L);
  teamSum<L>(f);
  return f;
}

// Pass 1 by the team of thread t (lane t % L of particle t / L).
template <int L, typename T>
__device__ void stressTeam(const MlsView<T>& s, std::int64_t t) {
  const std::int64_t i = t / L;
  const int lane = int(t % L);
  const Mat3<T> g = teamGradient<L>(s, i, lane);
  if (i < s.n && lane == 0) mlsStressAt(s, i, g);
}

template <typename T, int L>
__global__ void stressKernel(MlsView<T> s) {
  stressTeam<L>(s, std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x);
}

template <typename T, int L>
__global__ void forceKernel(MlsView<T> s, T half_dt, bool kick) {
  const std::int64_t t = std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x, k = t / L;
  const int lane = int(t % L);
  const Vec3<T> f = teamForce<L>(s, k, lane);
  if (k < s.n && lane == 0) mlsForceAt(s, k, f, half_dt, kick);
}

// The end of one substep and the start of the next, fused (graph path): particle k's force gather and second
// half kick, then its first half kick and drift of the next substep. Each uses only k's own force, so this is
// the same per-particle sequence as forceKernel then driftKernel.
template <typename T, int L>
__global__ void forceDriftKernel(MlsView<T> s, T half_dt, T dt, int remaining) {
  const std::int64_t t = std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x, k = t / L;
  const int lane = int(t % L);
  const Vec3<T> f = teamForce<L>(s, k, lane);
  if (k >= s.n || lane != 0) return;
  mlsForceAt(s, k, f, half_dt, true);
  mlsDriftPass(s, k, dt, remaining);
}

// Coupling groups (eqs. 11-13): a team per group adds its members' sums (the displacements, and for a rotating
// group sum u q^T), lane 0 finishes the group (its rotation, springs and shares).
template <int L, typename T>
__device__ void couplingTeam(const CouplingView<T>& c, const Vec3<T>* u, std::int64_t t) {
  const std::int64_t g = t / L;
  const int lane = int(t % L);
  CouplingSums<T> sums;
  if (g < c.groups) sums = couplingMemberSums(c, u, std::int32_t(g), lane, L);
  teamSum<L>(sums.u);
  // Every lane of the warp, whatever its group: a warp holds several teams, and a full-mask shuffle that only some
  // of them reach never completes (a non-rotating group adds zeros).
  teamSum<L>(sums.uq);
  if (g < c.groups && lane == 0) couplingGroupFinish(c, std::int32_t(g), sums);
}

template <typename T, int L>
__global__ void couplingKernel(CouplingView<T> c, const Vec3<T>* u) {
  couplingTeam<L>(c, u, std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x);
}

// Graph path: pass 1 and the coupling groups in one launch (both only read the drifted displacement; they write
// disjoint arrays, and the force pass after them reads both): the first stress_blocks blocks take the particles,
// the rest the groups.
template <typename T, int L>
__global__ void stressCouplingKernel(MlsView<T> s, CouplingView<T> c, unsigned stress_blocks) {
  if (blockIdx.x < stress_blocks)
    stressTeam<L>(s, std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x);
  else
    couplingTeam<L>(c, s.displacement, std::int64_t(blockIdx.x - stress_blocks) * blockDim.x + threadIdx.x);
}

// The substeps of one frame in one cooperative launch: the graph path's kernels (drift; then per substep the
// stress and coupling teams, then the force gather with the second half kick and the next drift) as phases of one
// persistent grid, separated by grid-wide barriers instead of kernel boundaries. Each phase walks the same thread
// indices as its kernel (grid-stride), calls the same per-particle functions with the same lane teams, so every
// value is the graph path's, bit for bit. Loop bounds are rounded up to whole warps so that a team's shuffles
// always see all 32 lanes (lanes past the end add zeros, as in the kernels).
template <typename T, int L>
__global__ void substepsPersistentKernel(MlsView<T> s, CouplingView<T> c, bool coupling, T dt, T half_dt, int n) {
  cooperative_groups::grid_group grid = cooperative_groups::this_grid();
  const std::int64_t stride = std::int64_t(gridDim.x) * blockDim.x;
  const std::int64_t t0 = std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  const auto warps = [](std::int64_t threads) { return (threads + 31) / 32 * 32; };
  const std::int64_t team_threads = warps(s.n * L);
  const std::int64_t group_threads = coupling ? warps(std::int64_t(c.groups) * L) : 0;
  for (std::int64_t k = t0; k < s.n; k += stride) mlsDriftPass(s, k, dt, n);
  grid.sync();
  for (int step = 0; step < n; ++step) {
    for (std::int64_t t = t0; t < team_threads; t += stride) stressTeam<L>(s, t);
    for (std::int64_t t = t0; t < group_threads; t += stride) couplingTeam<L>(c, s.displacement, t);
    grid.sync();
    const int remaining = n - step - 1;
    for (std::int64_t t = t0; t < team_threads; t += stride) {
      const std::int64_t k = t / L;
      const Vec3<T> f = teamForce<L>(s, k, int(t % L));
      if (k >= s.n || t % L != 0) continue;
      mlsForceAt(s, k, f, half_dt, true);
      if (remaining > 0) mlsDriftPass(s, k, dt, remaining);
    }
    if (remaining > 0) grid.sync();
  }
}

// Tools: particle idx[p] (unique, validated on the host) becomes prescribed with target tgt[p], unless fixed.
template <typename T>
__global__ void prescribeKernel(const std::int32_t* idx, const Vec3<T>* tgt, std::int64_t count, std::uint8_t* kind,
                                Vec3<T>* target) {
  const std::int64_t p = std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (p >= count) return;
  const std::int32_t i = idx[p];
  if (kind[i] == kMlsFixed) return;
  kind[i] = kMlsPrescribed;
  target[i] = tgt[p];
}

// Per block: kinetic, gravity potential, elastic energy sums, max |u|^2, and the lowest non-finite index
// with its stage (0 integrate, 1 forces, 2 stress), packed as index * 4 + stage (n * 4 when none).
struct Partial {
  double kinetic, potential, elastic, max_u2, stiffening;
  long long bad;
};

// Stiffening per particle over the full grid (a neighbour loop: too much work for the fixed reduction grid).
template <typename T, int L>
__global__ void stiffeningKernel(MlsView<T> s, T* out) {
  const std::int64_t t = std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x, i = t / L;
  const int lane = int(t % L);
  const Mat3<T> g = teamGradient<L>(s, i, lane);
  if (i < s.n && lane == 0) out[i] = mlsStiffeningOf(g, s.coeffs);
}

// Lanes per particle: a team of 8 while the teams fill at most about a GPU's resident threads (~270k on an
// H100); one lane above.
constexpr std::int64_t kTeamMaxParticles = 32768;
constexpr int kTeamLanes = 8;

// Calls launch(lanes) with lanes a std::integral_constant of the lane count for a model of n points (the kernels
// take it as a template argument; every launch of one model uses the same count).
template <typename Launch>
void withLanes(std::int64_t n, Launch&& launch) {
  if (n <= kTeamMaxParticles)
    launch(std::integral_constant<int, kTeamLanes>{});
  else
    launch(std::integral_constant<int, 1>{});
}

template <typename T>
__global__ void reduceKernel(MlsView<T> s, const T* stiffening, Partial* out) {
  __shared__ double ke[kBlock], pe[kBlock], el[kBlock], mu[kBlock], sf[kBlock];
  __shared__ long long bad[kBlock];
  double k_sum = 0, p_sum = 0, e_sum = 0, m = 0, stiff = 1;
  long long b = s.n * 4;
  for (std::int64_t i = std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x; i < s.n;
       i += std::int64_t(gridDim.x) * blockDim.x) {
    if (!mlsParticleFinite(s, i)) {
      const int stage = !(isFinite(s.displacement[i]) && isFinite(s.velocity[i])) ? 0 : (!isFinite(s.force[i]) ? 1 : 2);
      const long long code = (long long)i * 4 + stage;
      b = code < b ? code : b;
      continue;
    }
    k_sum += double(mlsKineticEnergy(s, i));
    p_sum += double(mlsGravityEnergy(s, i));
    e_sum += double(s.energy[i]);
    const double u2 = double(norm2(s.displacement[i]));
    m = u2 > m ? u2 : m;
    const double k = double(stiffening[i]);
    stiff = k > stiff ? k : stiff;
  }
  const int t = threadIdx.x;
  ke[t] = k_sum;
  pe[t] = p_sum;
  el[t] = e_sum;
  mu[t] = m;
  sf[t] = stiff;
  bad[t] = b;
  __syncthreads();
  for (int w = kBlock / 2; w > 0; w /= 2) {
    if (t < w) {
      ke[t] += ke[t + w];
      pe[t] += pe[t + w];
      el[t] += el[t + w];
      mu[t] = mu[t] > mu[t + w] ? mu[t] : mu[t + w];
      sf[t] = sf[t] > sf[t + w] ? sf[t] : sf[t + w];
      bad[t] = bad[t] < bad[t + w] ? bad[t] : bad[t + w];
    }
    __syncthreads();
  }
  if (t == 0) out[blockIdx.x] = Partial{ke[0], pe[0], el[0], mu[0], sf[0], bad[0]};
}

template <typename T>
void uploadVec(DeviceBuffer<T>& d, const std::vector<T>& h) {
  d.upload(h);
}

template <typename T>
class MlsCudaSolver final : public MlsSolver {
 public:
  explicit MlsCudaSolver(MlsModel<T> model) {
    // A blocking stream: it is ordered after the legacy-stream copies of DeviceBuffer::upload/download
    // (a pageable cudaMemcpy may return before its DMA lands; a kernel on a non-blocking stream could race it).
    INC_CUDA(cudaStreamCreate(&stream_));
    load(std::move(model));
  }
  using MlsSolver::replaceModel;  // the other precision's overload: refused (false)
  bool replaceModel(MlsModel<T>& model) override {
    load(std::move(model));  // load() waits for the device first: queued work may still read the old buffers
    return true;
  }
  ~MlsCudaSolver() override {
    if (graph_exec_) cudaGraphExecDestroy(graph_exec_);
    for (cudaEvent_t e : events_) cudaEventDestroy(e);
    if (stream_) cudaStreamDestroy(stream_);
  }

  BackendKind backend() const override { return BackendKind::Cuda; }
  Precision precision() const override { return sizeof(T) == 8 ? Precision::Float64 : Precision::Float32; }
  std::size_t size() const override { return model_.size(); }
  const MlsModelStats& modelStats() const override { return model_.stats; }
  Vec3d origin() const override { return model_.origin; }
  std::vector<Vec3d> restPositions() const override {
    std::vector<Vec3d> out(model_.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = model_.origin + Vec3d(model_.rest[i]);
    return out;
  }

  void computeForces() override {
    const MlsView<T> s = view();
    if (s.n == 0) return;
    couplingPass();
    launchStress(s);
    launchForce(s, T(0), false);
    forces_valid_ = true;
  }

  void step(double dt, int n) override {
    if (!(dt > 0) || !(dt <= stableTimeStep() * (1.0 + 1e-12)))
      throw InputError(model_.source, "dt",
                       "time step " + std::to_string(dt) + " s is outside (0, stable limit " +
                           std::to_string(stableTimeStep()) + " s]; refused");
    if (n <= 0) return;
    uploadBlade(dt, n);
    uploadStatics();
    substeps(T(dt), n, false);
    INC_CUDA(cudaStreamSynchronize(stream_));  // step() returns with the state final (tests, benchmarks)
  }

  MlsFrameStats advance(double frame_dt, int fixed_substeps) override {
    return frame(frame_dt, fixed_substeps, nullptr);
  }

  MlsFrameStats advanceCoupled(double frame_dt, int fixed_substeps, std::vector<Vec3d>& group_u) override {
    if (stage_timing_ || groups_ == 0) return MlsSolver::advanceCoupled(frame_dt, fixed_substeps, group_u);
    return frame(frame_dt, fixed_substeps, &group_u);
  }

  // One frame; with `group_u` (untimed stages only), the groups' eq. 13 displacements read back with the reduction:
  // queued before it (it reads none of what the coupling pass writes), they arrive with its wait.
  MlsFrameStats frame(double frame_dt, int fixed_substeps, std::vector<Vec3d>* group_u) {
    MlsFrameStats st;
    st.substeps = planFrame(frame_dt, fixed_substeps, model_.source);
    if (st.substeps == 0) {
      st = unplannableFrame();
      if (group_u) couplingDisplacements(*group_u);
      return st;
    }
    st.dt = frame_dt / st.substeps;
    uploadBlade(st.dt, st.substeps);
    uploadStatics();
    if (!stage_timing_) {
      ensureEvents(2);
      INC_CUDA(cudaEventRecord(events_[0], stream_));
      if (!persistent_ || !substepsPersistent(T(st.dt), st.substeps)) substepsGraph(T(st.dt), st.substeps);
      INC_CUDA(cudaEventRecord(events_[1], stream_));
      if (group_u) {
        couplingPass();
        group_staging_.queueDownload(cg_displacement_.data(), std::size_t(groups_), stream_);
      }
      const auto t0 = std::chrono::steady_clock::now();
      st.totals = reduce();  // synchronises: the once-per-frame download
      st.ms_reduce = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (group_u) {
        std::vector<Vec3<T>> g(static_cast<std::size_t>(groups_));
        group_staging_.take(g.data(), g.size());
        group_u->resize(g.size());
        for (std::size_t k = 0; k < g.size(); ++k) (*group_u)[k] = Vec3d(g[k]);
      }
      float ms = 0;
      INC_CUDA(cudaEventElapsedTime(&ms, events_[0], events_[1]));
      st.ms_substeps = ms;
      return st;
    }
    substeps(T(st.dt), st.substeps, true);
    const auto t0 = std::chrono::steady_clock::now();
    st.totals = reduce();  // synchronises: the once-per-frame download
    st.ms_reduce = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    // Stage times from the events recorded around each stage of each substep (the stream is idle now).
    for (int k = 0; k < st.substeps; ++k) {
      float a = 0, cp = 0, b = 0, c = 0;
      INC_CUDA(cudaEventElapsedTime(&a, events_[5 * k], events_[5 * k + 1]));
      INC_CUDA(cudaEventElapsedTime(&cp, events_[5 * k + 1], events_[5 * k + 2]));
      INC_CUDA(cudaEventElapsedTime(&b, events_[5 * k + 2], events_[5 * k + 3]));
      INC_CUDA(cudaEventElapsedTime(&c, events_[5 * k + 3], events_[5 * k + 4]));
      st.ms_integrate += a;
      st.ms_coupling += cp;
      st.ms_stress += b;
      st.ms_forces += c;
    }
    return st;
  }

  void setStageTiming(bool on) override { stage_timing_ = on; }
  void setPersistentSubsteps(bool on) override { persistent_ = on; }

  // The model's arrays into the device buffers (grown as needed), the state at rest, no coupling groups.
  void load(MlsModel<T> model) {
    model_ = std::move(model);
    resetSolverState(model_.safety);
    const std::size_t n = model_.size();
    // No kernel still reads the old model's buffers: they all run on stream_ (the device-wide wait also waited for
    // the PBD model's upload that a cut runs beside this one on another thread).
    INC_CUDA(cudaStreamSynchronize(stream_));
    bulk_.add(rest_, model_.rest);
    bulk_.add(mass_, model_.mass);
    bulk_.add(volume_, model_.volume);
    bulk_.add(moment_inverse_, model_.moment_inverse);
    bulk_.add(kind_, model_.kind);
    bulk_.add(offsets_, model_.neighbors.offsets);
    bulk_.add(indices_, model_.neighbors.indices);
    for (DeviceBuffer<Vec3<T>>* b : {&u_, &v_, &f_, &target_}) bulk_.zero(*b, n);
    bulk_.zero(stress_moment_, n);
    bulk_.zero(energy_, n);
    bulk_.flush(stream_);  // one wait instead of a synchronous copy per array
    stiffening_buf_.resize(n);
    partials_.resize(kReduceBlocks);
    groups_ = 0;
    springs_ = 0;
    forces_valid_ = false;
    has_checkpoint_ = false;
    graph_key_.clear();  // the graph's kernels hold the model's constants (support, coefficients): re-capture
  }

  MlsReduction reduce() override {
    if (!forces_valid_) computeForces();
    const MlsView<T> s = view();
    MlsReduction r;
    if (s.n == 0) return r;
    withLanes(s.n, [&](auto lanes) {
      constexpr int L = decltype(lanes)::value;
      stiffeningKernel<T, L><<<gridFor(s.n * L), kBlock, 0, stream_>>>(s, stiffening_buf_.data());
    });
    INC_CUDA_LAUNCH("mls stiffeningKernel");
    reduceKernel<T><<<kReduceBlocks, kBlock, 0, stream_>>>(s, stiffening_buf_.data(), partials_.data());
    INC_CUDA_LAUNCH("mls reduceKernel");
    std::vector<Partial> p(kReduceBlocks);
    INC_CUDA(
        cudaMemcpyAsync(p.data(), partials_.data(), kReduceBlocks * sizeof(Partial), cudaMemcpyDeviceToHost, stream_));
    INC_CUDA(cudaStreamSynchronize(stream_));
    double max_u2 = 0;
    long long bad = s.n * 4;
    for (const Partial& q : p) {  // block order: deterministic
      r.kinetic_energy += q.kinetic;
      r.potential_energy += q.potential;
      r.elastic_energy += q.elastic;
      max_u2 = std::max(max_u2, q.max_u2);
      r.stiffening = std::max(r.stiffening, q.stiffening);
      bad = std::min(bad, q.bad);
    }
    r.max_displacement = std::sqrt(max_u2);
    if (bad < s.n * 4) {
      r.finite = false;
      r.first_bad = bad / 4;
      const int stage = int(bad % 4);
      r.bad_stage = stage == 0 ? "integrate" : (stage == 1 ? "forces" : "stress");
    }
    noteReduction(r);
    return r;
  }

  void setDisplacements(const std::vector<Vec3d>& u) override {
    upload(u_, u, "displacements");
    forces_valid_ = false;
    forgetStiffening();
  }
  void setVelocities(const std::vector<Vec3d>& v) override { upload(v_, v, "velocities"); }
  void displacements(std::vector<Vec3d>& out) const override { download(u_, out); }
  void velocities(std::vector<Vec3d>& out) const override { download(v_, out); }
  void forces(std::vector<Vec3d>& out) const override { download(f_, out); }
  void energies(std::vector<double>& out) const override {
    INC_CUDA(cudaStreamSynchronize(stream_));
    const std::vector<T> e = energy_.download();
    out.assign(e.begin(), e.end());
  }

  // Only the listed particles travel: a compact (index, target) upload and a scatter kernel (indices are
  // unique after validation, so no two threads write one particle).
  void setPrescribed(const std::vector<std::int32_t>& particles, const std::vector<Vec3d>& targets) override {
    if (targets.size() != particles.size())
      throw std::invalid_argument("MlsSolver: one target per prescribed particle");
    std::vector<std::int32_t> idx;
    std::vector<Vec3<T>> tgt;
    std::vector<char> seen(size(), 0);
    for (std::size_t p = 0; p < particles.size(); ++p) {
      const std::int32_t i = particles[p];
      if (i < 0 || std::size_t(i) >= size()) throw std::invalid_argument("MlsSolver: prescribed particle out of range");
      if (model_.kind[std::size_t(i)] == kMlsFixed || seen[std::size_t(i)]) continue;
      seen[std::size_t(i)] = 1;
      model_.kind[std::size_t(i)] = kMlsPrescribed;
      idx.push_back(i);
      tgt.push_back(Vec3<T>(targets[p]));
    }
    if (idx.empty()) return;
    INC_CUDA(cudaStreamSynchronize(stream_));  // the staging buffers may still be read by the previous scatter
    pres_idx_.upload(idx);
    pres_tgt_.upload(tgt);
    prescribeKernel<T><<<gridFor(std::int64_t(idx.size())), kBlock, 0, stream_>>>(
        pres_idx_.data(), pres_tgt_.data(), std::int64_t(idx.size()), kind_.data(), target_.data());
    INC_CUDA_LAUNCH("mls prescribeKernel");
  }
  void release(const std::vector<std::int32_t>& particles) override {
    for (const std::int32_t i : particles) {
      if (i < 0 || std::size_t(i) >= size()) throw std::invalid_argument("MlsSolver: released particle out of range");
      if (model_.kind[std::size_t(i)] == kMlsPrescribed) model_.kind[std::size_t(i)] = kMlsFree;
    }
    INC_CUDA(cudaStreamSynchronize(stream_));
    kind_.upload(model_.kind);  // rare (a tool lets go): one upload of the kind array
  }

  // Groups in precision T relative to the model origin; one upload per topology change.
  void setCouplingGroups(const MlsCouplingGroups& g) override {
    validateMlsCouplingGroups(g, size());
    groups_ = std::int32_t(g.size());
    springs_ = g.springs();
    std::vector<Vec3<T>> centre(g.size()), anchor(g.springs());
    for (std::size_t k = 0; k < g.size(); ++k) centre[k] = Vec3<T>(g.rest_centres[k] - model_.origin);
    // Until anchors arrive every spring sits at its rest length from the group's rest centre (no force).
    for (std::size_t k = 0; k < g.size(); ++k)
      for (std::int32_t q = g.spring_offsets[k]; q < g.spring_offsets[k + 1]; ++q)
        anchor[std::size_t(q)] = centre[k] + Vec3<T>(T(g.rest_lengths[std::size_t(q)]), T(0), T(0));
    std::vector<std::int32_t> group(size(), -1);
    for (std::size_t k = 0; k < g.size(); ++k)
      for (std::int32_t p = g.member_offsets[k]; p < g.member_offsets[k + 1]; ++p)
        group[std::size_t(g.members[std::size_t(p)])] = std::int32_t(k);
    INC_CUDA(cudaStreamSynchronize(stream_));  // queued substeps may still read the old groups
    bulk_.add(cg_member_offsets_, g.member_offsets);
    bulk_.add(cg_members_, g.members);
    bulk_.add(cg_spring_offsets_, g.spring_offsets);
    bulk_.add(cg_rest_centre_, centre);
    bulk_.add(cg_anchor_, anchor);
    bulk_.add(cg_rest_length_, std::vector<T>(g.rest_lengths.begin(), g.rest_lengths.end()));
    bulk_.add(cg_stiffness_, std::vector<T>(g.stiffnesses.begin(), g.stiffnesses.end()));
    bulk_.add(particle_group_, group);
    bulk_.zero(cg_displacement_, g.size());
    bulk_.zero(cg_force_, g.size());
    const MlsCouplingFrames frames = mlsCouplingFrames(g, restPositions());
    const MlsCouplingFrameArrays<T> fa = mlsCouplingFrameArrays<T>(frames, model_.origin);
    bulk_.add(cg_centroid_, fa.centroid);
    bulk_.add(cg_gram_, fa.gram);
    bulk_.add(cg_inertia_inverse_, fa.inertia_inverse);
    bulk_.add(cg_rotation_, std::vector<pbd::Quat<T>>(g.size()));
    bulk_.zero(cg_torque_, g.size());
    bulk_.flush(stream_);
    setCouplingStableStep(
        mlsCouplingStableStep(g, std::vector<double>(model_.mass.begin(), model_.mass.end()), &frames));
    forces_valid_ = false;
  }
  void setCouplingAnchors(const std::vector<Vec3d>& anchors) override {
    if (anchors.size() != springs_)
      throw std::invalid_argument("MlsSolver: coupling anchors has " + std::to_string(anchors.size()) +
                                  " entries for " + std::to_string(springs_) + " springs");
    std::vector<Vec3<T>> a(anchors.size());
    for (std::size_t q = 0; q < a.size(); ++q) a[q] = Vec3<T>(anchors[q] - model_.origin);
    INC_CUDA(cudaStreamSynchronize(stream_));  // the previous anchors may still be read by queued substeps
    cg_anchor_.upload(a);
    forces_valid_ = false;
  }
  // One small download per call (n_groups vectors): the exchange the PBD side needs.
  void couplingDisplacements(std::vector<Vec3d>& out) override {
    couplingPass();
    download(cg_displacement_, out);
  }

  void saveCheckpoint() override {
    saved_u_.resize(size());
    saved_v_.resize(size());
    copy(saved_u_, u_);
    copy(saved_v_, v_);
    saved_rotation_.resize(cg_rotation_.size());  // the groups' warm starts: a retried step repeats the same extraction
    copy(saved_rotation_, cg_rotation_);
    has_checkpoint_ = true;
  }
  void restoreCheckpoint() override {
    if (!has_checkpoint_) return;
    copy(u_, saved_u_);
    copy(v_, saved_v_);
    if (saved_rotation_.size() == cg_rotation_.size()) copy(cg_rotation_, saved_rotation_);
    forces_valid_ = false;
    forgetStiffening();
  }

  MemoryReport memory() const override {
    MemoryReport m;
    m.device_bytes =
        rest_.capacityBytes() + mass_.capacityBytes() + volume_.capacityBytes() + moment_inverse_.capacityBytes() +
        kind_.capacityBytes() + offsets_.capacityBytes() + indices_.capacityBytes() + u_.capacityBytes() +
        v_.capacityBytes() + f_.capacityBytes() + target_.capacityBytes() + stress_moment_.capacityBytes() +
        energy_.capacityBytes() + stiffening_buf_.capacityBytes() + cg_member_offsets_.capacityBytes() +
        cg_members_.capacityBytes() + cg_spring_offsets_.capacityBytes() + particle_group_.capacityBytes() +
        cg_rest_centre_.capacityBytes() + cg_anchor_.capacityBytes() + cg_displacement_.capacityBytes() +
        cg_force_.capacityBytes() + cg_rest_length_.capacityBytes() + cg_stiffness_.capacityBytes() +
        cg_centroid_.capacityBytes() + cg_gram_.capacityBytes() + cg_inertia_inverse_.capacityBytes() +
        cg_torque_.capacityBytes() + cg_rotation_.capacityBytes() + saved_rotation_.capacityBytes() +
        partials_.capacityBytes() + saved_u_.capacityBytes() + saved_v_.capacityBytes();
    m.host_bytes = model_.bytes();
    return m;
  }

 private:
  MlsView<T> view() {
    MlsView<T> v;
    v.n = std::int64_t(model_.size());
    v.rest = rest_.data();
    v.mass = mass_.data();
    v.volume = volume_.data();
    v.moment_inverse = moment_inverse_.data();
    v.kind = kind_.data();
    v.offsets = offsets_.data();
    v.indices = indices_.data();
    v.support = model_.support;
    v.coeffs = model_.coeffs;
    v.gravity = model_.gravity;
    v.displacement = u_.data();
    v.velocity = v_.data();
    v.force = f_.data();
    v.target = target_.data();
    v.stress_moment = stress_moment_.data();
    v.energy = energy_.data();
    if (bladeOn()) v.blade = blade_buf_.data();
    if (staticsOn()) v.statics = statics_buf_.data();
    if (groups_ > 0) {
      v.coupling_group = particle_group_.data();
      v.coupling_force = cg_force_.data();
      v.coupling_torque = cg_torque_.data();
      v.coupling_centroid = cg_centroid_.data();
    }
    return v;
  }

  CouplingView<T> couplingView() {
    CouplingView<T> c;
    c.groups = groups_;
    c.member_offsets = cg_member_offsets_.data();
    c.members = cg_members_.data();
    c.rest_centre = cg_rest_centre_.data();
    c.spring_offsets = cg_spring_offsets_.data();
    c.anchor = cg_anchor_.data();
    c.rest_length = cg_rest_length_.data();
    c.stiffness = cg_stiffness_.data();
    c.group_displacement = cg_displacement_.data();
    c.member_force = cg_force_.data();
    c.member_rest = rest_.data();
    c.rest_centroid = cg_centroid_.data();
    c.rest_gram = cg_gram_.data();
    c.inertia_inverse = cg_inertia_inverse_.data();
    c.rotation = cg_rotation_.data();
    c.member_torque = cg_torque_.data();
    return c;
  }
  void couplingPass() {
    if (groups_ == 0) return;
    withLanes(std::int64_t(model_.size()), [&](auto lanes) {
      constexpr int L = decltype(lanes)::value;
      couplingKernel<T, L><<<gridFor(std::int64_t(groups_) * L), kBlock, 0, stream_>>>(couplingView(), u_.data());
    });
    INC_CUDA_LAUNCH("mls couplingKernel");
  }

  void launchStress(const MlsView<T>& s) {
    withLanes(s.n, [&](auto lanes) {
      constexpr int L = decltype(lanes)::value;
      stressKernel<T, L><<<gridFor(s.n * L), kBlock, 0, stream_>>>(s);
    });
    INC_CUDA_LAUNCH("mls stressKernel");
  }
  // Pass 1 and the coupling pass in one launch (graph path); without groups, pass 1 alone.
  void launchStressCoupling(const MlsView<T>& s) {
    if (groups_ == 0) return launchStress(s);
    withLanes(s.n, [&](auto lanes) {
      constexpr int L = decltype(lanes)::value;
      const unsigned stress_blocks = unsigned(gridFor(s.n * L));
      const unsigned blocks = stress_blocks + unsigned(gridFor(std::int64_t(groups_) * L));
      stressCouplingKernel<T, L><<<blocks, kBlock, 0, stream_>>>(s, couplingView(), stress_blocks);
    });
    INC_CUDA_LAUNCH("mls stressCouplingKernel");
  }
  void launchForce(const MlsView<T>& s, T half_dt, bool kick) {
    withLanes(s.n, [&](auto lanes) {
      constexpr int L = decltype(lanes)::value;
      forceKernel<T, L><<<gridFor(s.n * L), kBlock, 0, stream_>>>(s, half_dt, kick);
    });
    INC_CUDA_LAUNCH("mls forceKernel");
  }
  void launchForceDrift(const MlsView<T>& s, T half_dt, T dt, int remaining) {
    withLanes(s.n, [&](auto lanes) {
      constexpr int L = decltype(lanes)::value;
      forceDriftKernel<T, L><<<gridFor(s.n * L), kBlock, 0, stream_>>>(s, half_dt, dt, remaining);
    });
    INC_CUDA_LAUNCH("mls forceDriftKernel");
  }

  // n substeps of dt, all launched asynchronously on the stream; with `timed`, events around each stage.
  void substeps(T dt, int n, bool timed) {
    if (!forces_valid_) computeForces();
    const MlsView<T> s = view();
    if (s.n == 0) return;
    if (timed) ensureEvents(std::size_t(5) * std::size_t(n));
    const T half = T(0.5) * dt;
    const int grid = gridFor(s.n);
    for (int k = 0; k < n; ++k) {
      if (timed) INC_CUDA(cudaEventRecord(events_[5 * k], stream_));
      driftKernel<T><<<grid, kBlock, 0, stream_>>>(s, dt, n - k);
      INC_CUDA_LAUNCH("mls driftKernel");
      if (timed) INC_CUDA(cudaEventRecord(events_[5 * k + 1], stream_));
      couplingPass();  // the groups' spring forces at the drifted displacement, before the force gather
      if (timed) INC_CUDA(cudaEventRecord(events_[5 * k + 2], stream_));
      launchStress(s);
      if (timed) INC_CUDA(cudaEventRecord(events_[5 * k + 3], stream_));
      launchForce(s, half, true);
      if (timed) INC_CUDA(cudaEventRecord(events_[5 * k + 4], stream_));
    }
  }

  // n substeps of dt as one CUDA graph, captured once and replayed while n, dt and the buffers stay the same
  // (replaceModel re-captures). The kernels are those of substeps() with the coupling pass in the stress launch
  // and each force pass fused with the next drift (forceDriftKernel): two dependent launches per substep, not four.
  void substepsGraph(T dt, int n) {
    if (!forces_valid_) computeForces();
    const MlsView<T> s = view();
    if (s.n == 0 || n <= 0) return;
    const T half = T(0.5) * dt;
    const std::vector<std::uint64_t> key = graphKey(dt, n);
    if (!graph_exec_ || key != graph_key_) {
      captureGraph(stream_, graph_exec_, [&] {
        const int grid = gridFor(s.n);
        driftKernel<T><<<grid, kBlock, 0, stream_>>>(s, dt, n);
        INC_CUDA_LAUNCH("mls driftKernel");
        for (int k = 0; k < n; ++k) {
          launchStressCoupling(s);
          if (k + 1 < n) {
            launchForceDrift(s, half, dt, n - k - 1);
          } else {
            launchForce(s, half, true);
          }
        }
      });
      graph_key_ = key;
    }
    INC_CUDA(cudaGraphLaunch(graph_exec_, stream_));
  }

  // n substeps of dt in one cooperative launch (substepsPersistentKernel): false, with nothing launched, where the
  // device has no cooperative launch or the grid the model needs cannot be resident at once (the caller replays
  // the graph instead). The grid: the graph path's blocks for the teams, at most what the SMs hold together.
  bool substepsPersistent(T dt, int n) {
    if (n <= 0) return true;
    const MlsView<T> s = view();
    if (s.n == 0) return true;
    bool launched = false;
    withLanes(s.n, [&](auto lanes) {
      constexpr int L = decltype(lanes)::value;
      const auto kernel = substepsPersistentKernel<T, L>;
      if (coop_blocks_ < 0 || coop_lanes_ != L) {  // asked once per lane count (a model's size class)
        int dev = 0, coop = 0, sms = 0, per_sm = 0;
        INC_CUDA(cudaGetDevice(&dev));
        INC_CUDA(cudaDeviceGetAttribute(&coop, cudaDevAttrCooperativeLaunch, dev));
        INC_CUDA(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev));
        INC_CUDA(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, kernel, kBlock, 0));
        coop_blocks_ = coop ? per_sm * sms : 0;
        coop_lanes_ = L;
      }
      const std::int64_t want = std::max<std::int64_t>(gridFor(s.n * L), gridFor(std::int64_t(groups_) * L));
      if (coop_blocks_ <= 0 || want > coop_blocks_) return;
      if (!forces_valid_) computeForces();
      CouplingView<T> c = couplingView();
      bool coupling = groups_ > 0;
      T step = dt, half = T(0.5) * dt;
      int count = n;
      MlsView<T> sv = s;
      void* args[] = {&sv, &c, &coupling, &step, &half, &count};
      INC_CUDA(cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(kernel), dim3(unsigned(want)), dim3(kBlock),
                                           args, 0, stream_));
      INC_CUDA_LAUNCH("mls substepsPersistentKernel");
      launched = true;
    });
    return launched;
  }

  // What the captured graph depends on besides buffer contents: the substep count and size, the particle and
  // group counts, and every buffer the coupling may have reallocated (setCouplingGroups uploads new arrays).
  std::vector<std::uint64_t> graphKey(T dt, int n) {
    const double dt_d = double(dt);
    std::uint64_t dt_bits = 0;
    std::memcpy(&dt_bits, &dt_d, sizeof dt_bits);
    const CouplingView<T> c = couplingView();
    const auto bits = [](const void* p) { return std::uint64_t(reinterpret_cast<std::uintptr_t>(p)); };
    return {std::uint64_t(n),
            dt_bits,
            std::uint64_t(model_.size()),
            std::uint64_t(groups_),
            bits(particle_group_.data()),
            bits(c.member_offsets),
            bits(c.members),
            bits(c.rest_centre),
            bits(c.spring_offsets),
            bits(c.anchor),
            bits(c.rest_length),
            bits(c.stiffness),
            bits(c.group_displacement),
            bits(c.member_force),
            bits(c.rest_centroid),
            bits(c.rest_gram),
            bits(c.inertia_inverse),
            bits(c.rotation),
            bits(c.member_torque),
            bits(bladeOn() ? blade_buf_.data() : nullptr),
            bits(staticsOn() ? statics_buf_.data() : nullptr)};
  }

  // The blade of the coming substeps, one small upload (only where a blade contact is set). The stream is idle here
  // (the last advance ended in its reduction's download), so nothing queued still reads the buffer.
  void uploadBlade(double dt, int n) {
    if (!bladeOn()) return;
    const MlsBladeContact<T> c = bladeContact<T>(dt, n);
    INC_CUDA(cudaStreamSynchronize(stream_));
    blade_buf_.upload(&c, 1);
  }

  // The static colliders relative to the origin, uploaded when they or the origin (a replaced model) changed.
  void uploadStatics() {
    if (!staticsOn()) return;
    const Vec3d o = origin();
    if (statics_uploaded_ == staticsVersion() && o.x == statics_origin_.x && o.y == statics_origin_.y &&
        o.z == statics_origin_.z)
      return;
    const MlsStaticContacts<T> c = staticContacts<T>();
    INC_CUDA(cudaStreamSynchronize(stream_));
    statics_buf_.upload(&c, 1);
    statics_uploaded_ = staticsVersion();
    statics_origin_ = o;
  }

  void ensureEvents(std::size_t count) {
    while (events_.size() < count) {
      cudaEvent_t e;
      INC_CUDA(cudaEventCreate(&e));
      events_.push_back(e);
    }
  }

  void upload(DeviceBuffer<Vec3<T>>& d, const std::vector<Vec3d>& h, const char* what) {
    if (h.size() != size())
      throw std::invalid_argument(std::string("MlsSolver: ") + what + " has " + std::to_string(h.size()) +
                                  " entries for " + std::to_string(size()) + " particles");
    std::vector<Vec3<T>> t(h.size());
    for (std::size_t i = 0; i < h.size(); ++i) t[i] = Vec3<T>(h[i]);
    INC_CUDA(cudaStreamSynchronize(stream_));
    d.upload(t);
  }
  void download(const DeviceBuffer<Vec3<T>>& d, std::vector<Vec3d>& out) const {
    INC_CUDA(cudaStreamSynchronize(stream_));
    const std::vector<Vec3<T>> t = d.download();
    out.resize(t.size());
    for (std::size_t i = 0; i < t.size(); ++i) out[i] = Vec3d(t[i]);
  }
  template <typename E>
  void copy(DeviceBuffer<E>& dst, const DeviceBuffer<E>& src) {
    if (src.size()) INC_CUDA(cudaMemcpyAsync(dst.data(), src.data(), src.bytes(), cudaMemcpyDeviceToDevice, stream_));
  }

  MlsModel<T> model_;
  PinnedStaging group_staging_;  // advanceCoupled's read-back of the groups' displacements
  DeviceBuffer<Vec3<T>> rest_;
  DeviceBuffer<T> mass_, volume_;
  DeviceBuffer<Mat3<T>> moment_inverse_;
  DeviceBuffer<std::uint8_t> kind_;
  DeviceBuffer<std::int64_t> offsets_;
  DeviceBuffer<std::int32_t> indices_;
  DeviceBuffer<Vec3<T>> u_, v_, f_, target_, saved_u_, saved_v_;
  DeviceBuffer<Mat3<T>> stress_moment_;
  DeviceBuffer<T> energy_, stiffening_buf_;
  DeviceBuffer<Partial> partials_;
  DeviceBuffer<std::int32_t> pres_idx_;
  DeviceBuffer<Vec3<T>> pres_tgt_;
  DeviceBuffer<std::int32_t> cg_member_offsets_, cg_members_, cg_spring_offsets_, particle_group_;
  DeviceBuffer<Vec3<T>> cg_rest_centre_, cg_anchor_, cg_displacement_, cg_force_;
  DeviceBuffer<T> cg_rest_length_, cg_stiffness_;
  DeviceBuffer<Vec3<T>>
      cg_centroid_;  // rotation-aware eq. 13: rest frames, rotations, moments (physics/cut_coupling.h)
  DeviceBuffer<Mat3<T>> cg_gram_, cg_inertia_inverse_, cg_torque_;
  DeviceBuffer<pbd::Quat<T>> cg_rotation_, saved_rotation_;
  DeviceBuffer<MlsBladeContact<T>> blade_buf_;          // one entry: MlsView::blade while bladeOn()
  DeviceBuffer<MlsStaticContacts<T>> statics_buf_;      // one entry: MlsView::statics while staticsOn()
  std::uint64_t statics_uploaded_ = ~std::uint64_t(0);  // the staticsVersion() in statics_buf_
  Vec3d statics_origin_;                                // the origin it was made relative to
  std::int32_t groups_ = 0;
  std::size_t springs_ = 0;
  cudaStream_t stream_ = nullptr;
  std::vector<cudaEvent_t> events_;
  bool forces_valid_ = false;
  bool stage_timing_ = true;
  bool persistent_ = true;  // untimed frames as one cooperative launch where it fits (substepsPersistent)
  int coop_blocks_ = -1;    // blocks the device holds at once for the persistent kernel (-1: not asked yet)
  int coop_lanes_ = 0;      // the lane count coop_blocks_ was asked for
  cudaGraphExec_t graph_exec_ = nullptr;  // substepsGraph's frame, for graph_key_
  BulkUpload bulk_;                       // load() and setCouplingGroups() uploads
  std::vector<std::uint64_t> graph_key_;
  bool has_checkpoint_ = false;
};

}  // namespace

std::unique_ptr<MlsSolver> makeMlsSolverCuda(MlsModel<float> model) {
  return std::make_unique<MlsCudaSolver<float>>(std::move(model));
}
std::unique_ptr<MlsSolver> makeMlsSolverCuda(MlsModel<double> model) {
  return std::make_unique<MlsCudaSolver<double>>(std::move(model));
}

}  // namespace inc::cuda
