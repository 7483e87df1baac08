// Drives a tearable sheet frame by frame: PBD/XPBD solve, grasper pull, tearing step, model rebuild on topology change, removal tools.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "host/backend.h"
#include "host/pbd_model.h"
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

  const TearSheet<T>& sheet() const { return sheet_; }
  TearSheet<T>& mutableSheet() { return sheet_; }  // call resetModel() after editing
  void resetModel();
  TearParams<T>& tearParams() { return tear_; }
  PbdStepParams<T>& stepParams() { return step_; }
  bool tearing_enabled = true;
  BackendKind kind() const { return tear_backend_->kind(); }
  MemoryReport memory() const { return pbd_->memory(); }

 private:
  TearSheet<T> sheet_;
  TearParams<T> tear_;
  TearModelOptions model_opt_;
  PbdStepParams<T> step_;
  std::unique_ptr<PbdBackend<T>> pbd_;
  std::unique_ptr<TearStepBackend<T>> tear_backend_;
  PbdState<T> state_;
};

}  // namespace inc
