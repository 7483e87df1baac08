// The CUDA PBD/XPBD backend class: its device-resident model and state, and where each of its parts is defined.
#pragma once

#include <cuda_runtime.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/bulk_upload.h"
#include "kernels/cuda_check.h"
#include "kernels/device_buffer.h"
#include "kernels/device_grow.h"
#include "kernels/pbd_chebyshev_args.cuh"
#include "kernels/pbd_contact_kernels.cuh"
#include "kernels/pbd_device_cuda.h"
#include "kernels/pbd_frame_data.cuh"
#include "kernels/pbd_frame_path.cuh"
#include "kernels/pbd_launch.cuh"
#include "kernels/pinned_staging.h"
#include "model/pbd_model.h"
#include "physics/pbd_block.h"

namespace inc::cuda {

template <typename T>
struct DeviceBlock {
  PbdConstraintKind kind = PbdConstraintKind::Distance;
  bool solve = true;
  T stiffness = T(1);
  int count = 0;
  DeviceBuffer<std::int32_t> offsets, ids, particle_offsets, particle_slots, order;
  DeviceBuffer<T> rest, compliance, jacobi_scale;
  DeviceBuffer<Vec3<T>> rest_vec, lambda, slot_corr;
  DeviceBuffer<Vec3<T>> cheb1, cheb2;            // Chebyshev: multipliers one and two iterations back (sized on demand)
  std::vector<std::int32_t> color_offsets;       // host: launch ranges
  DeviceBuffer<std::int32_t> color_offsets_dev;  // the same, for the fused small-model kernel
};

// What a captured graph depends on besides stable buffer pointers; a change re-captures.
template <typename T>
struct GraphKey {
  PbdStepParams<T> p;
  std::size_t kinematic = 0, tools = 0, volume_tools = 0;
  std::size_t attached = 0;
  const void* ptrs[11] = {};  // frame-input buffers
  // Grid sizes of the particle and per-block launches (PbdCudaBackend::gridCount: buckets once the model was patched,
  // the counts themselves in the single-kernel frames, which take them as arguments).
  int n = 0;
  int counts[kMaxLiveBlocks] = {};
  bool patched = false;
  std::uint64_t topo = 0;  // PbdCudaBackend::topo_version_
};

// The backend, one class over several files (each defines the members of one concern; without relocatable device
// code a kernel is launched from the file that defines it or through a wrapper declared in a kernels/pbd_*.cuh):
// - kernels/pbd_solver_cuda.cu: model upload and state (setModel, setState, getState, memory), the factory;
// - kernels/pbd_frame_cuda.cu: a frame's orchestration (advanceFrame, frame inputs, the per-block launches,
//   Chebyshev iterates, stage profiling);
// - kernels/pbd_frame_path.cuh: which frame path runs; kernels/pbd_whole_frame_cuda.cu: planning and launching the
//   single-launch frames (fused, cluster, grid);
// - kernels/pbd_graph_cuda.cu: capturing the frame into a CUDA graph and replaying it;
// - kernels/pbd_summary_cuda.cu: the residual, finiteness and volume summary;
// - kernels/pbd_patch_cuda.cu: the PbdDevicePatch API (the model patched on the device after a tear).
// The per-block frame's kernels are in kernels/pbd_particle_kernels.cu, pbd_projection_kernels.cu and
// pbd_contact_kernels.cu. pbd_solver_cuda.cu instantiates the class for float and double; every other file
// instantiates the members it defines that another file calls.
template <typename T>
class PbdCudaBackend final : public PbdBackend<T>, public PbdDevicePatch<T> {
 public:
  PbdCudaBackend();
  ~PbdCudaBackend() override;
  PbdCudaBackend(const PbdCudaBackend&) = delete;
  PbdCudaBackend& operator=(const PbdCudaBackend&) = delete;

  BackendKind kind() const override { return BackendKind::Cuda; }

  void setModel(const PbdModel<T>& m) override;
  void setState(const PbdState<T>& s) override;
  void getPositions(std::vector<Vec3<T>>& positions) const override;
  void getState(PbdState<T>& s) const override;
  MemoryReport memory() const override;
  PbdFrameStats advanceFrame(const PbdStepParams<T>& p, const PbdFrameInput<T>& in) override;

  // PbdDevicePatch (kernels/pbd_patch_cuda.cu)
  PbdDeviceParticles<T> deviceParticles() override;
  void reserveParticles(std::size_t particles) override;
  void appendParticles(int n_new, const std::uint8_t* fixed_dev) override;
  PbdDeviceBlock<T> reserveBlock(int block, std::size_t constraints) override;
  void commitBlock(int block, int count) override;
  PbdDeviceIncidence reserveIncidence(int block, std::size_t constraints) override;
  void commitBlockIncidence(int block, int count) override;
  void setSummaryEvery(int k) override;
  PbdConstraintBlock<T> downloadBlock(int block) const override;
  std::vector<T> downloadInverseMasses() const override;
  void setBlockFromHost(int block, const std::vector<std::int32_t>& ids, const std::vector<T>& rest,
                        const std::vector<T>& compliance) override;
  void appendParticlesFromHost(const std::vector<Vec3<T>>& rest, const std::vector<Vec3<T>>& x,
                               const std::vector<Vec3<T>>& v, const std::vector<T>& mass,
                               const std::vector<std::uint8_t>& fixed) override;

 private:
  // What every per-block launch of one frame shares (recordFrame).
  struct LaunchFrame {
    T dt = T(0), damp = T(1);
    pbd::SolveContext<T> ctx;
    unsigned gn = 0;              // blocks of the particle launches (over gridCount(n_))
    unsigned gcont = 0;           // blocks of the contact launches (the particles, or every Chebyshev multiplier)
    const int* live_n = nullptr;  // the particle count on the device (patched models)
    bool cheb = false;            // Chebyshev-accelerated
    ChebyshevArgs<T> ch;          // mode and weight set per iteration
    int last_solved = -1;         // the last block solved
    bool fuse_contacts = false;   // the contacts ride on the last block's gather
    PbdContactScene<T> scene;
  };
  struct ProfRecord {
    int stage;
    std::size_t start, stop;
  };

  // --- a frame's orchestration (kernels/pbd_frame_cuda.cu)
  void recordProfiledFrame(const PbdStepParams<T>& p, PbdFrameStats& st);
  void recordTimedFrame(const PbdStepParams<T>& p, const PbdFrameInput<T>& in, PbdFrameStats& st);
  void uploadFrameInput(const PbdFrameInput<T>& in);
  void ensureChebyshev(const PbdStepParams<T>& p);
  ChebyshevArgs<T> chebyshevArgs();
  void recordDirectFrame(const PbdStepParams<T>& p);
  void recordFrame(const PbdStepParams<T>& p);
  FusedFrame<T> wholeFrameArgs(const PbdStepParams<T>& p, const pbd::SolveContext<T>& ctx, T dt, T damp);
  void recordSubstep(const PbdStepParams<T>& p, LaunchFrame& lf, int s);
  void recordIteration(const PbdStepParams<T>& p, LaunchFrame& lf, int it, T t_start, T t_end);
  void recordRotations(const LaunchFrame& lf);
  void recordRadii(const PbdStepParams<T>& p, const LaunchFrame& lf);
  void ensureEvents(std::size_t k);
  std::size_t stageBegin();
  void stageEnd(int stage, std::size_t k);
  bool summaryDue() const { return frame_count_ % std::uint64_t(summary_every_) == 0; }

  // --- the single-launch frames (kernels/pbd_whole_frame_cuda.cu)
  void updateStaging();
  void planCluster(int forced_ctas);
  void planGrid();
  void launchWholeFrame(FramePath path, const PbdStepParams<T>& p, const FusedFrame<T>& f);
  void launchGridFrame(const PbdStepParams<T>& p, const FusedFrame<T>& f);
  void printClusterProfile();

  // --- graph capture (kernels/pbd_graph_cuda.cu)
  void launchGraphFrame(const PbdStepParams<T>& p, const PbdFrameInput<T>& in);
  void destroyGraph() {
    if (graph_exec_) cudaGraphExecDestroy(graph_exec_);
    graph_exec_ = nullptr;
  }

  // --- the frame's summary (kernels/pbd_summary_cuda.cu)
  void summarize(const PbdStepParams<T>& p, PbdFrameStats& st);

  // --- topology patches (kernels/pbd_patch_cuda.cu)
  void commit(int block, int count, bool caller_csr);
  void sortIncidence(DeviceBlock<T>& d, std::size_t slots);
  DeviceBlock<T>& patchBlock(int block);
  void uploadLive();

  // --- shared
  // The device's per-block shared-memory limit (opt-in).
  static int sharedOptin() {
    int dev = 0, optin = 0;
    INC_CUDA(cudaGetDevice(&dev));
    INC_CUDA(cudaDeviceGetAttribute(&optin, cudaDevAttrMaxSharedMemoryPerBlockOptin, dev));
    return optin;
  }

  pbd::BlockView<T> view(DeviceBlock<T>& d) {
    pbd::BlockView<T> b;
    b.kind = int(d.kind);
    b.count = d.count;
    b.stiffness = d.stiffness;
    b.offsets = d.offsets.data();
    b.ids = d.ids.data();
    b.rest = d.rest.data();
    b.rest_vec = d.rest_vec.data();
    b.compliance = d.compliance.data();
    b.jacobi_scale = d.jacobi_scale.data();
    b.particle_offsets = d.particle_offsets.data();
    b.particle_slots = d.particle_slots.data();
    b.lambda = d.lambda.data();
    b.slot_corr = d.slot_corr.data();
    return b;
  }

  // Grid size of a launch over `count` particles or constraints: the count itself until the model is patched on the
  // device, then a bucket (a multiple of max(2048, 1/32 of the next power of two)), so that a tearing frame's few
  // hundred new particles and constraints keep the captured graph: its kernels stop at the live count, and it is
  // re-captured when the count crosses into the next bucket (about every 3 % of growth). The bucket costs at most
  // 1/32 more (empty) blocks.
  int gridCount(int count) const {
    if (!patched_ || count <= 0) return count;
    int g = 2048;
    while (g < count / 32) g *= 2;
    return (count + g - 1) / g * g;
  }

  // Bytes a frame's memset clears in a buffer of the live count: its gridCount bucket within the capacity (at least
  // the size), so that the captured size does not change with every patch.
  template <typename U>
  std::size_t bucketBytes(const DeviceBuffer<U>& b) const {
    return std::min(capacityOf(b), std::size_t(gridCount(int(b.size())))) * sizeof(U);
  }

  // The frame path this frame takes (kernels/pbd_frame_path.cuh).
  FramePath framePath(const PbdStepParams<T>& p) const {
    FramePathFacts f;
    f.particles = n_;
    f.blocks = int(blocks_.size());
    f.profiling = profile_;
    f.patched = patched_;
    f.direct = direct_frame_;
    f.cluster_planned = cluster_ok_;
    f.grid_resident_blocks = grid_cap_;
    return chooseFramePath(p, f);
  }

  cudaStream_t stream_ = nullptr;
  cudaGraphExec_t graph_exec_ = nullptr;
  BulkUpload bulk_;  // setModel's uploads
  GraphKey<T> graph_key_;
  bool has_coloring_ = true;      // Gauss-Seidel needs every solved block coloured (pbdModelHasColoring)
  DeviceBuffer<T> cheb_weights_;  // the grid frame's per-iteration weights
  std::vector<T> cheb_weights_host_;
  int grid_cap_ = -1;          // resident blocks of the grid frame (planGrid); -1 not asked yet
  bool direct_frame_ = false;  // the frame being recorded is launched directly, not captured
  DeviceBuffer<Vec3<T>> cheb_x1_, cheb_x2_, cheb_a1_, cheb_a2_;  // Chebyshev: positions, attachment multipliers
  std::uint64_t topo_version_ = 0;  // bumped by a new model and by a reallocation: the captured graph holds pointers
  DeviceBuffer<int> live_;          // the counts the frame's kernels read (uploadLive)
  std::vector<std::int32_t> kin_ids_host_;  // what kin_ids_ holds
  PinnedStaging summary_staging_, kin_to_staging_;
  bool live_dirty_ = true;
  std::uint64_t last_direct_topo_ = ~std::uint64_t(0);
  bool patched_ = false;  // a block was rebuilt on the device: no colouring (Jacobi only)
  int summary_every_ = 1;
  std::uint64_t frame_count_ = 0;
  DeviceBuffer<std::uint32_t> sort_keys_, sort_keys_out_;
  DeviceBuffer<std::int32_t> sort_vals_;
  DeviceBuffer<unsigned char> cub_temp_;
  std::vector<cudaEvent_t> events_;
  std::vector<ProfRecord> prof_;
  bool profile_ = false;

  int n_ = 0, n_planes_ = 0, n_boxes_ = 0, n_kin_ = 0, n_att_ = 0, n_tools_ = 0, n_volume_tools_ = 0,
      rotation_block_ = -1;
  bool have_volume_data_ = false;
  std::vector<T> host_rest_radii_;
  DeviceBuffer<T> inset_;  // PbdModel::contact_inset where the model has one
  bool has_inset_ = false;
  const T* insetPtr() const { return has_inset_ ? inset_.data() : nullptr; }
  DeviceBuffer<Vec3<T>> rest_positions_, x_, v_, x_prev_, kin_from_, kin_to_, samples_, att_from_, att_to_, att_lambda_;
  DeviceBuffer<T> masses_, inv_mass_, w_, rest_radii_, radii_, radii_next_, rest_cell_, att_comp_;
  DeviceBuffer<pbd::Quat<T>> rotations_;
  DeviceBuffer<std::uint8_t> active_, fixed_scratch_;
  DeviceBuffer<std::int32_t> kin_ids_, ov_off_, ov_ids_, att_ids_;
  DeviceBuffer<pbd::PlaneCollider<T>> planes_;
  DeviceBuffer<pbd::BoxCollider<T>> boxes_;
  DeviceBuffer<pbd::CapsuleCollider<T>> tools_from_, tools_to_;
  DeviceBuffer<double> partials_;  // reduction partials: per distance block (max, sum), then summary
  std::vector<double> host_partials_;
  struct ClusterBlockMeta {
    std::vector<std::int32_t> offsets;         // host copy of the block's constraint -> slot offsets
    std::vector<std::int32_t> particle_slots;  // and of its particle -> slot CSR entries
    bool solve = true;
    int kind = 0;
  };
  std::vector<ClusterBlockMeta> cluster_meta_;
  const char* last_path_ = "launches";  // the frame kernel recordFrame chose last (reported in the stats)
  std::vector<DeviceBuffer<std::int32_t>> cluster_home_;  // ClusterSplit::slot_home, per block
  DeviceBuffer<long long> cluster_profile_;               // INCISION_PBD_CLUSTER_PROFILE: cycles per phase kind and CTA
  int cluster_planned_for_ = -1;                          // the cluster_ctas the current plan was made for (-1: none)
  bool cluster_ok_ = false;                               // the cluster frame can run this model (planCluster)
  ClusterSplit cluster_split_;
  std::size_t cluster_bytes_ = 0;
  bool staged_ = false;  // fused kernel stages particles in shared memory
  std::size_t stage_bytes_ = 0;
  std::vector<DeviceBlock<T>> blocks_;
};

}  // namespace inc::cuda
