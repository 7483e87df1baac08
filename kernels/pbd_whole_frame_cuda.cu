// The CUDA PBD backend's single-launch frames: planning (kernel attributes, the cluster's split, the grid's size) and
// launching the fused, cluster and grid frame kernels.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "kernels/pbd_backend_cuda.cuh"
#include "kernels/pbd_cluster_frame.cuh"
#include "kernels/pbd_fused_frame.cuh"
#include "kernels/pbd_grid_frame.cuh"
#include "kernels/pbd_group_projection.cuh"

namespace inc::cuda {

// Shared-memory staging of the fused kernel: used when the model fits this device's per-block opt-in limit
// (float: up to ~6,000 particles on an H100); the attribute is set here, outside any graph capture.
template <typename T>
void PbdCudaBackend<T>::updateStaging() {
  const int optin = sharedOptin();
  stage_bytes_ = fusedStageBytes<T>(n_);
  staged_ = n_ > 0 && stage_bytes_ <= std::size_t(optin);
  // The attribute belongs to the kernel, not to this backend: set it to the device limit so that a second
  // live backend with a smaller model cannot lower it below what this one launches with.
  if (staged_) INC_CUDA(cudaFuncSetAttribute(fusedFrameKernel<T>, cudaFuncAttributeMaxDynamicSharedMemorySize, optin));
}

// The thread-block cluster frame (kernels/pbd_cluster_frame.cuh): how many CTAs, which constraints and slots
// each projects, which particles each owns. Decided per model (host offsets at hand); usable when the device
// launches clusters and every CTA's replica fits its shared memory. Attributes are set here, outside captures.
template <typename T>
void PbdCudaBackend<T>::planCluster(int forced_ctas) {
  if (cluster_planned_for_ == forced_ctas) return;
  cluster_planned_for_ = forced_ctas;
  cluster_ok_ = false;
  if (n_ == 0 || cluster_meta_.empty() || cluster_meta_.size() > std::size_t(kMaxFusedBlocks) ||
      forced_ctas > kMaxClusterCtas)
    return;
  int dev = 0, major = 0;
  INC_CUDA(cudaGetDevice(&dev));
  INC_CUDA(cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, dev));
  if (major < 9) return;  // clusters and distributed shared memory: Hopper (sm_90) and newer
  cudaFuncAttributes fa{};
  INC_CUDA(cudaFuncGetAttributes(&fa, clusterFrameKernel<T>));
  const int dyn_max = sharedOptin() - int(fa.sharedSizeBytes);  // static shared memory counts against the limit
  // Enough CTAs that every cluster constraint gets its lanes and every scalar constraint its thread in one
  // pass (fewer CTAs: cheaper barriers), capped at the largest cluster the hardware allows.
  const int groups_per_cta = kClusterThreads / pbdgroup::kGroup;
  int want = (n_ + kClusterThreads - 1) / kClusterThreads;
  for (const ClusterBlockMeta& b : cluster_meta_) {
    const int c = int(b.offsets.size()) - 1;
    if (!b.solve || c <= 0) continue;
    const bool group = pbdgroup::usesGroup(b.kind);
    want =
        std::max(want, group ? (c + groups_per_cta - 1) / groups_per_cta : (c + kClusterThreads - 1) / kClusterThreads);
  }
  int ctas = forced_ctas > 0 ? forced_ctas : std::min(want, kMaxClusterCtas);
  ClusterSplit sp;
  for (; ctas >= 1; --ctas) {
    sp = ClusterSplit{};
    sp.ctas = ctas;
    sp.chunk = (n_ + ctas - 1) / ctas;
    for (std::size_t bi = 0; bi < cluster_meta_.size(); ++bi) {
      const ClusterBlockMeta& b = cluster_meta_[bi];
      const std::int64_t c = std::int64_t(b.offsets.size()) - 1;
      for (int r = 0; r <= ctas; ++r) {
        sp.c_split[bi][r] = int(c * r / ctas);
        sp.s_split[bi][r] = c > 0 ? b.offsets[std::size_t(sp.c_split[bi][r])] : 0;
      }
      if (b.solve)
        for (int r = 0; r < ctas; ++r) sp.max_share = std::max(sp.max_share, sp.s_split[bi][r + 1] - sp.s_split[bi][r]);
    }
    const std::size_t bytes = clusterStageBytes<T>(n_, sp.max_share);
    if (bytes > std::size_t(dyn_max)) break;  // fewer CTAs never shrink the replica
    INC_CUDA(cudaFuncSetAttribute(clusterFrameKernel<T>, cudaFuncAttributeMaxDynamicSharedMemorySize, dyn_max));
    INC_CUDA(cudaFuncSetAttribute(clusterFrameKernel<T>, cudaFuncAttributeNonPortableClusterSizeAllowed, 1));
    ClusterLaunch launch(ctas, bytes, nullptr);
    int clusters = 0;
    if (cudaOccupancyMaxActiveClusters(&clusters, clusterFrameKernel<T>, &launch.cfg) != cudaSuccess) {
      (void)cudaGetLastError();  // not sticky: this size cannot be launched
      clusters = 0;
    }
    if (clusters < 1) {
      if (forced_ctas > 0) return;  // the forced size cannot run here: per-launch path
      continue;
    }
    // Each particle-slot entry's home: the CTA that projects its constraint and its place in that CTA's
    // slot buffer.
    cluster_home_.resize(cluster_meta_.size());
    for (std::size_t bi = 0; bi < cluster_meta_.size(); ++bi) {
      const ClusterBlockMeta& b = cluster_meta_[bi];
      std::vector<std::int32_t> home(b.particle_slots.size());
      for (std::size_t k = 0; k < home.size(); ++k) {
        const std::int32_t slot = b.particle_slots[k];
        int r = 0;
        while (r + 1 < ctas && sp.s_split[bi][r + 1] <= slot) ++r;
        home[k] = std::int32_t((std::uint32_t(r) << 24) | std::uint32_t(slot - sp.s_split[bi][r]));
      }
      cluster_home_[bi].upload(home);
      sp.slot_home[bi] = cluster_home_[bi].data();
    }
    if (std::getenv("INCISION_PBD_CLUSTER_PROFILE")) {
      cluster_profile_.resize(std::size_t(ctas) * kClusterProfileSlots);
      sp.profile = cluster_profile_.data();
    }
    cluster_split_ = sp;
    cluster_bytes_ = bytes;
    cluster_ok_ = true;
    return;
  }
}

// The grid frame's resident-grid limit (blocks of kGridFrameThreads that the device holds at once), asked once per
// backend outside any capture; 0 where the device has no cooperative launch.
template <typename T>
void PbdCudaBackend<T>::planGrid() {
  if (grid_cap_ >= 0) return;
  int dev = 0, coop = 0, sms = 0, per_sm = 0;
  INC_CUDA(cudaGetDevice(&dev));
  INC_CUDA(cudaDeviceGetAttribute(&coop, cudaDevAttrCooperativeLaunch, dev));
  INC_CUDA(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev));
  INC_CUDA(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, gridFrameKernel<T>, kGridFrameThreads, 0));
  grid_cap_ = coop ? per_sm * sms : 0;
}

// One cooperative launch of the whole frame: as many blocks as the widest phase wants (a cluster constraint's
// lanes, a scalar constraint's thread, a particle's, a multiplier's), at most the resident grid.
template <typename T>
void PbdCudaBackend<T>::launchGridFrame(const PbdStepParams<T>& p, const FusedFrame<T>& f) {
  GridFrame<T> g;
  g.f = f;
  std::int64_t want = std::max<std::int64_t>({n_, n_att_, n_kin_});
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
    const DeviceBlock<T>& d = blocks_[bi];
    if (!d.solve || d.count == 0) continue;
    g.last_solved = int(bi);
    const bool group = pbdgroup::usesGroup(int(d.kind));
    want = std::max<std::int64_t>(want, group ? std::int64_t(d.count) * pbdgroup::kGroup : d.count);
  }
  if (p.chebyshev_rho > T(0)) {
    g.ch = chebyshevArgs();
    g.cheb_weights = cheb_weights_.data();
    g.cheb_rho = p.chebyshev_rho;
    want = std::max<std::int64_t>(want, g.ch.total);
  }
  const std::int64_t blocks = std::min<std::int64_t>(grid_cap_, (want + kGridFrameThreads - 1) / kGridFrameThreads);
  void* args[] = {&g};
  INC_CUDA(cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(gridFrameKernel<T>),
                                       dim3(unsigned(std::max<std::int64_t>(1, blocks))), dim3(kGridFrameThreads), args,
                                       0, stream_));
  INC_CUDA_LAUNCH("pbd grid frame");
}

// The frame as one launch of the chosen whole-frame kernel (kernels/pbd_frame_path.cuh).
template <typename T>
void PbdCudaBackend<T>::launchWholeFrame(FramePath path, const PbdStepParams<T>& p, const FusedFrame<T>& f) {
  if (path == FramePath::Grid) {
    launchGridFrame(p, f);
  } else if (path == FramePath::Cluster) {
    ClusterLaunch launch(cluster_split_.ctas, cluster_bytes_, stream_);
    INC_CUDA(cudaLaunchKernelEx(&launch.cfg, clusterFrameKernel<T>, f, cluster_split_));
    INC_CUDA_LAUNCH("pbd cluster frame");
  } else {
    fusedFrameKernel<T><<<1, kFusedThreads, staged_ ? stage_bytes_ : 0, stream_>>>(f);
    INC_CUDA_LAUNCH("pbd fused frame");
  }
}

// Diagnostics (INCISION_PBD_CLUSTER_PROFILE set): microseconds per phase kind of the last cluster frame, as
// CTA 0 and the slowest CTA saw them, on stderr.
template <typename T>
void PbdCudaBackend<T>::printClusterProfile() {
  INC_CUDA(cudaStreamSynchronize(stream_));
  const std::vector<long long> c = cluster_profile_.download();
  int dev = 0, khz = 0;
  INC_CUDA(cudaGetDevice(&dev));
  INC_CUDA(cudaDeviceGetAttribute(&khz, cudaDevAttrClockRate, dev));
  const char* what[4] = {"project", "sync", "gather", "sync"};
  std::fprintf(stderr, "cluster profile (%d CTAs, us: cta0/max):", cluster_split_.ctas);
  for (int k = 0; k < kClusterProfileSlots; ++k) {
    long long mx = 0;
    for (int r = 0; r < cluster_split_.ctas; ++r) mx = std::max(mx, c[std::size_t(r * kClusterProfileSlots + k)]);
    if (mx == 0) continue;
    if (k == 0)
      std::fprintf(stderr, " start");
    else
      std::fprintf(stderr, " b%d.%s", (k - 1) / 4, what[(k - 1) % 4]);
    std::fprintf(stderr, "=%.1f/%.1f", 1e3 * double(c[std::size_t(k)]) / khz, 1e3 * double(mx) / khz);
  }
  std::fprintf(stderr, "\n");
}

// Defined here, called from the other files of the backend (the class is instantiated in pbd_solver_cuda.cu).
template void PbdCudaBackend<float>::updateStaging();
template void PbdCudaBackend<double>::updateStaging();
template void PbdCudaBackend<float>::planCluster(int);
template void PbdCudaBackend<double>::planCluster(int);
template void PbdCudaBackend<float>::planGrid();
template void PbdCudaBackend<double>::planGrid();
template void PbdCudaBackend<float>::launchWholeFrame(FramePath, const PbdStepParams<float>&, const FusedFrame<float>&);
template void PbdCudaBackend<double>::launchWholeFrame(FramePath, const PbdStepParams<double>&,
                                                       const FusedFrame<double>&);
template void PbdCudaBackend<float>::printClusterProfile();
template void PbdCudaBackend<double>::printClusterProfile();

}  // namespace inc::cuda
