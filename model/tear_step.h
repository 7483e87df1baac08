// The tearing step's interface: what a step reports, its per-particle candidates, and the backend both solvers
// implement.
#pragma once

#include <cstdint>
#include <vector>

#include "model/backend.h"
#include "model/pbd_model.h"
#include "model/stage_timing.h"
#include "model/tearing_sheet.h"
#include "physics/vec3.h"

namespace inc {

struct TearStepStats {
  int yielding = 0;         // particles past the criterion whose split is possible
  int splits = 0;           // particles split this step (= new particles)
  int deferred = 0;         // yielding but sharing a triangle with a higher-priority yielding particle
  int moved_triangles = 0;  // triangles moved from split particles to their new particles
  int backed_off = 0;       // splits whose fraction t was reduced to keep triangles valid
};

// Per-particle results of the detection pass (kept for tests and the GPU parity check).
template <typename T>
struct TearCandidates {
  std::vector<std::uint8_t> yield;    // criterion passed and the split separates triangles
  std::vector<std::uint8_t> accept;   // in this step's independent set
  std::vector<std::int32_t> partner;  // j: the broken bond's other particle
  std::vector<Vec3<T>> dir;           // crack-opening direction (split plane normal), towards j
  std::vector<T> t_pred;              // predicted fraction before the random perturbation
};

struct TearFrameStats {
  int splits = 0;  // new particles this frame
  int yielding = 0;
  int deferred = 0;
  int removed = 0;               // particles removed by a tool this frame
  double solve_ms = 0.0;         // PBD frame
  double tear_ms = 0.0;          // detection + split + triangle rebuild
  double rebuild_ms = 0.0;       // adjacency + PBD model rebuild + upload after a topology change
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

}  // namespace inc
