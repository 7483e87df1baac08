// Drives a tearable sheet frame by frame: PBD/XPBD solve, grasper pull, tearing step, model rebuild on topology change, removal tools.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "host/backend.h"
#include "host/pbd_model.h"
#include "host/simulation_model.h"
#include "host/tearing_sheet.h"

namespace inc {

struct TearFrameStats {
  int splits = 0;            // new particles this frame
  int yielding = 0;
  int deferred = 0;
  int removed = 0;           // particles removed by a tool this frame
  double solve_ms = 0.0;     // PBD frame
  double tear_ms = 0.0;      // detection + split + triangle rebuild
  double rebuild_ms = 0.0;   // adjacency + PBD model rebuild + upload after a topology change
  bool device_resident = false;  // the frame ran on the device-resident path (no host sheet, model patched)
  // Wall-clock stages of the frame (ms). Always: the coarse ones; with TearingDriver::profile the device work
  // is synchronised around each stage so that each one holds its own GPU time, and the PBD backend's own
  // stages (CUDA events) follow as "pbd:<stage>".
  std::vector<StageTime> stages;
  PbdFrameStats pbd;
};

// Backend for the tearing step itself (the PBD solve uses the PBD backend of the same kind when available).
template <typename T>
class TearStepBackend {
 public:
  virtual ~TearStepBackend() = default;
  virtual BackendKind kind() const = 0;
  // One tearing step on `s` (positions and velocities current); returns new particles created. The
  // adjacency (rebuildTopology) is left to the caller, which rebuilds it together with the PBD model.
  virtual int step(TearSheet<T>& s, const TearParams<T>& p, TearFrameStats& st) = 0;

  // Device-resident path (CUDA with the Jacobi solver, docs/tearing.md). attach: takes the sheet (adjacency
  // current) and the PBD backend holding buildTearPbdModel(s, opt) with `model_blocks` blocks; false when
  // this backend cannot keep the sheet on the device (the host path is used).
  virtual bool attach(PbdBackend<T>& pbd, const TearSheet<T>& s, const TearModelOptions& opt, int model_blocks) {
    (void)pbd, (void)s, (void)opt, (void)model_blocks;
    return false;
  }
  // One tearing step on the device sheet (positions: the PBD backend's), then the device rebuild of the
  // adjacency and the patch of the PBD model; returns the new particles. profile: synchronise around stages.
  virtual int stepResident(const TearParams<T>& p, std::uint32_t step, TearFrameStats& st, bool profile) {
    (void)p, (void)step, (void)st, (void)profile;
    return 0;
  }
  virtual std::size_t residentSize() const { return 0; }
  // The device sheet into s. full: particles (rest, x, v, mass, fixed, k, tau_f) and triangles (the caller
  // rebuilds the adjacency; ref_normal and step are the caller's); else positions and velocities only (the
  // topology has not changed since the last full download).
  virtual void download(TearSheet<T>& s, bool full) { (void)s, (void)full; }
};

template <typename T>
std::unique_ptr<TearStepBackend<T>> makeTearStepBackend(BackendKind kind);

template <typename T>
class TearingDriver {
 public:
  TearingDriver(TearSheet<T> sheet, const TearParams<T>& tear, const TearModelOptions& model_opt,
                const PbdStepParams<T>& step, BackendKind kind);

  // One frame: grasped particles move linearly to grasp_to over the frame (kinematic), then the tearing
  // step (when enabled) and, if the topology changed, the model rebuild.
  TearFrameStats advance(const std::vector<std::int32_t>& grasp_ids, const std::vector<Vec3<T>>& grasp_to);
  // Removes tissue at once (traditional PBD, the paper's Fig. 5 a, c): marked particles, their triangles and
  // orphaned particles go. debris_fringe keeps a fringe (removeTearParticles). Returns particles removed.
  int removeParticles(const std::vector<std::uint8_t>& mark, bool debris_fringe = false,
                      std::vector<std::int32_t>* remap = nullptr);
  // Tears tissue out (the paper's Fig. 5 b, d): the marked particles are gripped and lifted by `lift` over
  // `frames` frames while the tearing criterion runs, so the surrounding tissue tears and leaves debris; then
  // the gripped particles are removed as above. Returns the splits made while lifting.
  int tearOut(const std::vector<std::uint8_t>& mark, const Vec3<T>& lift, int frames, int* removed = nullptr);

  // The host sheet. On the device-resident path it is downloaded (and its adjacency rebuilt) when stale: a
  // full copy, for output, tests and tools, never needed by advance().
  const TearSheet<T>& sheet() const {
    syncHost();
    return sheet_;
  }
  TearSheet<T>& mutableSheet() {  // call resetModel() after editing
    syncHost();
    return sheet_;
  }
  std::size_t particleCount() const { return resident_ ? tear_backend_->residentSize() : sheet_.size(); }
  void resetModel();
  TearParams<T>& tearParams() { return tear_; }
  PbdStepParams<T>& stepParams() { return step_; }
  bool tearing_enabled = true;
  // Per-stage timing with synchronisation between stages (slower; for the breakdown in bench_tearing).
  bool profile = false;
  // false: always the host path (host sheet, host rebuild, setModel), e.g. to compare against it.
  bool allow_device_resident = true;
  // The PBD residual/finiteness summary every k-th frame (device-resident path; the CPU always has it).
  void setSummaryEvery(int k);
  bool deviceResident() const { return resident_; }
  BackendKind kind() const { return tear_backend_->kind(); }
  MemoryReport memory() const { return pbd_->memory(); }
  PbdBackend<T>& pbdBackend() { return *pbd_; }  // the PBD backend (tests read its device model)

 private:
  mutable TearSheet<T> sheet_;  // mutable: sheet() downloads a stale device-resident sheet
  TearParams<T> tear_;
  TearModelOptions model_opt_;
  PbdStepParams<T> step_;
  std::unique_ptr<PbdBackend<T>> pbd_;
  std::unique_ptr<TearStepBackend<T>> tear_backend_;
  PbdState<T> state_;
  bool resident_ = false;
  mutable bool host_stale_ = false;   // positions/velocities on the host are older than the device's
  mutable bool topo_stale_ = false;   // and the topology too (a resident step made splits)
  int summary_every_ = 1;
  void syncHost() const;
  TearFrameStats advanceResident(const std::vector<std::int32_t>& grasp_ids, const std::vector<Vec3<T>>& grasp_to);
};

}  // namespace inc
