// Drives a tearable sheet frame by frame: PBD/XPBD solve, grasper pull, tearing step, model rebuild on topology change,
// removal tools.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "model/backend.h"
#include "model/pbd_model.h"
#include "model/stage_timing.h"
#include "model/tear_step.h"
#include "model/tearing_sheet.h"

namespace inc {

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
  mutable bool host_stale_ = false;  // positions/velocities on the host are older than the device's
  mutable bool topo_stale_ = false;  // and the topology too (a resident step made splits)
  int summary_every_ = 1;
  void syncHost() const;
  TearFrameStats advanceResident(const std::vector<std::int32_t>& grasp_ids, const std::vector<Vec3<T>>& grasp_to);
};

}  // namespace inc
