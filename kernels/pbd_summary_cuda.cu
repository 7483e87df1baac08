// The CUDA PBD backend's frame summary: residual, finiteness and volume statistics reduced on the device in a fixed
// order and downloaded once.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>

#include "kernels/pbd_backend_cuda.cuh"
#include "physics/pbd_block.h"

namespace inc::cuda {

namespace {

// Per-block partials of the distance residual: max and sum of squares (double), fixed tree order.
template <typename T>
__global__ void residualKernel(pbd::BlockView<T> b, const Vec3<T>* x, bool xpbd, T dt, double* part_max,
                               double* part_sum) {
  __shared__ double smax[kThreads];
  __shared__ double ssum[kThreads];
  double m = 0.0, s = 0.0;
  for (int c = blockIdx.x * blockDim.x + threadIdx.x; c < b.count; c += gridDim.x * blockDim.x) {
    const double r = double(pbd::distanceResidual(b, c, x, xpbd, dt));
    m = m > r ? m : r;
    s += r * r;
  }
  smax[threadIdx.x] = m;
  ssum[threadIdx.x] = s;
  __syncthreads();
  for (int h = blockDim.x / 2; h > 0; h /= 2) {
    if (threadIdx.x < h) {
      smax[threadIdx.x] = smax[threadIdx.x] > smax[threadIdx.x + h] ? smax[threadIdx.x] : smax[threadIdx.x + h];
      ssum[threadIdx.x] += ssum[threadIdx.x + h];
    }
    __syncthreads();
  }
  if (threadIdx.x == 0) {
    part_max[blockIdx.x] = smax[0];
    part_sum[blockIdx.x] = ssum[0];
  }
}

// Per-block partials over particles: first non-finite particle (n if none), active count, max radius ratio.
template <typename T>
__global__ void summaryKernel(int n, const Vec3<T>* x, const Vec3<T>* v, const T* r, const T* rest_r,
                              const std::uint8_t* active, double* part_bad, double* part_active, double* part_ratio) {
  __shared__ long long sbad[kThreads];
  __shared__ long long sact[kThreads];
  __shared__ double srat[kThreads];
  long long bad = n, act = 0;
  double rat = 1.0;
  for (int i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x) {
    // r - r is NaN exactly when r is NaN or infinite
    if ((!isFinite(x[i]) || !isFinite(v[i]) || !(r[i] - r[i] == T(0))) && i < bad) bad = i;
    act += active[i];
    if (rest_r[i] > T(0)) {
      const double q = double(r[i] / rest_r[i]);
      rat = rat > q ? rat : q;
    }
  }
  sbad[threadIdx.x] = bad;
  sact[threadIdx.x] = act;
  srat[threadIdx.x] = rat;
  __syncthreads();
  for (int h = blockDim.x / 2; h > 0; h /= 2) {
    if (threadIdx.x < h) {
      sbad[threadIdx.x] = sbad[threadIdx.x] < sbad[threadIdx.x + h] ? sbad[threadIdx.x] : sbad[threadIdx.x + h];
      sact[threadIdx.x] += sact[threadIdx.x + h];
      srat[threadIdx.x] = srat[threadIdx.x] > srat[threadIdx.x + h] ? srat[threadIdx.x] : srat[threadIdx.x + h];
    }
    __syncthreads();
  }
  if (threadIdx.x == 0) {
    part_bad[blockIdx.x] = double(sbad[0]);  // exact: indices and counts are far below 2^53
    part_active[blockIdx.x] = double(sact[0]);
    part_ratio[blockIdx.x] = srat[0];
  }
}

// The summary's partial groups reduced on the device: the used[g] partials of group g (its reduction's grid) ->
// totals[g], one block per group in a fixed tree order. Groups 0 .. 2 nd - 1 are the distance blocks' (max, sum)
// pairs, then (min, sum, max) of summaryKernel. One small download instead of all the partials.
struct FinishPlan {
  int nd = 0;
  int used[2 * kMaxLiveBlocks + 3] = {};
};
__global__ void __launch_bounds__(kReduceBlocks)
    finishPartialsKernel(const double* part, FinishPlan plan, double* totals) {
  __shared__ double s[kReduceBlocks];
  const int g = blockIdx.x, t = threadIdx.x, nd = plan.nd;
  const int op =
      g < 2 * nd ? (g % 2 == 0 ? 2 : 0) : (g == 2 * nd ? 1 : (g == 2 * nd + 1 ? 0 : 2));  // 0 sum, 1 min, 2 max
  const double identity = op == 0 ? 0.0 : (op == 1 ? DBL_MAX : -DBL_MAX);
  s[t] = t < plan.used[g] ? part[std::size_t(g) * kReduceBlocks + t] : identity;
  __syncthreads();
  for (int h = kReduceBlocks / 2; h > 0; h /= 2) {
    if (t < h) {
      const double a = s[t], b = s[t + h];
      s[t] = op == 0 ? a + b : (op == 1 ? (a < b ? a : b) : (a > b ? a : b));
    }
    __syncthreads();
  }
  if (t == 0) totals[g] = s[0];
}

}  // namespace

// Residual, finiteness and volume statistics: small partial reductions downloaded once per frame (the
// frame's one synchronisation, needed to report them).
template <typename T>
void PbdCudaBackend<T>::summarize(const PbdStepParams<T>& p, PbdFrameStats& st) {
  // All partials go to slices of one buffer: the frame's one synchronisation and one small download.
  const T dt = p.frame_dt / T(p.substeps);
  double* part = partials_.data();
  std::size_t rcount = 0;
  int nd = 0;
  FinishPlan plan;
  for (DeviceBlock<T>& d : blocks_) {
    if (d.kind != PbdConstraintKind::Distance || !d.solve || d.count == 0) continue;
    plan.used[2 * nd] = plan.used[2 * nd + 1] = reduceBlocksFor(d.count);
    residualKernel<T><<<plan.used[2 * nd], kThreads, 0, stream_>>>(view(d), x_.data(), p.xpbd, dt,
                                                                   part + std::size_t(2 * nd) * kReduceBlocks,
                                                                   part + std::size_t(2 * nd + 1) * kReduceBlocks);
    INC_CUDA_LAUNCH("pbd residual");
    rcount += std::size_t(d.count);
    ++nd;
  }
  double* sum_part = part + std::size_t(2 * nd) * kReduceBlocks;
  if (n_ > 0) {
    plan.used[2 * nd] = plan.used[2 * nd + 1] = plan.used[2 * nd + 2] = reduceBlocksFor(n_);
    summaryKernel<T><<<plan.used[2 * nd], kThreads, 0, stream_>>>(
        n_, x_.data(), v_.data(), radii_.data(), rest_radii_.data(), active_.data(), sum_part, sum_part + kReduceBlocks,
        sum_part + 2 * kReduceBlocks);
    INC_CUDA_LAUNCH("pbd summary");
  }
  const int groups = 2 * nd + (n_ > 0 ? 3 : 0);
  if (groups == 0) {
    INC_CUDA(cudaStreamSynchronize(stream_));
    return;
  }
  // The totals live after the partials (partials_ has room: see setModel and commit).
  double* totals = part + std::size_t(groups) * kReduceBlocks;
  plan.nd = nd;
  finishPartialsKernel<<<groups, kReduceBlocks, 0, stream_>>>(part, plan, totals);
  INC_CUDA_LAUNCH("pbd summary totals");
  host_partials_.resize(std::size_t(groups));
  summary_staging_.download(host_partials_.data(), totals, std::size_t(groups), stream_);  // waits for the frame
  const double* h = host_partials_.data();
  double rmax = 0, rsum = 0;
  for (int b = 0; b < nd; ++b) {
    rmax = std::max(rmax, h[2 * b]);
    rsum += h[2 * b + 1];
  }
  st.residual_max = rmax;
  st.residual_rms = rcount ? std::sqrt(rsum / double(rcount)) : 0.0;
  if (n_ > 0) {
    const double* hs = h + 2 * nd;
    const long long bad = (long long)hs[0], act = (long long)hs[1];
    const double rat = std::max(1.0, hs[2]);
    st.volume_active = int(act);
    st.max_radius_ratio = rat;
    if (bad < n_) {
      st.finite = false;
      st.failure_particle = bad;
    }
  }
}

// Defined here, called from the other files of the backend (the class is instantiated in pbd_solver_cuda.cu).
template void PbdCudaBackend<float>::summarize(const PbdStepParams<float>&, PbdFrameStats&);
template void PbdCudaBackend<double>::summarize(const PbdStepParams<double>&, PbdFrameStats&);

}  // namespace inc::cuda
