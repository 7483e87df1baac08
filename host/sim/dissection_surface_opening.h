// The surface opened during a stroke (cutting.open_surface_frames > 0): split on a worker, shown frames later.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "base/background_task.h"
#include "host/assembly/metaball_model.h"
#include "host/assembly/skin_binding.h"
#include "host/cut/cut_surface_state.h"
#include "host/cut/cut_swept_surface.h"
#include "host/io/mesh.h"
#include "host/sim/dissection_skin.h"

namespace inc::dissection {

// What an opening shows instead of the surface before the stroke: the split mesh, its wall flags and its skin.
struct OpenedSurface {
  TriangleMesh mesh;
  std::vector<std::uint8_t> wall;
  Skin skin;
};

// An opening's inputs and result: the surface as it was before the stroke split along every cut so far (the
// stroke's sweep so far last, a slit ending where the blade is) and the skin of the split surface bound to the
// stroke's base spheres across every cut. Display only: no simulated result depends on it.
struct OpeningJob {
  double launched_at = 0;  // s: the start of the frame it was started in
  int frames_left = 0;
  bool on_worker = false;                          // started on the worker (else computed when due)
  std::vector<SweptSurface> cuts;                  // the earlier cuts, then the stroke's sweep so far
  MetaballModel spheres;                           // the stroke's base
  std::shared_ptr<const CutSurfaceState> surface;  // the surface before the stroke
  std::string file;
  CutSurfaceState state;  // a copy of it, then split
  bool split = false;
  SkinBinding skin;
  double worker_ms = 0;
};

// An opening's split and binding (pure: the same job gives the same result on any thread). A sweep the split
// refuses (or any failure of it) leaves job.split false.
void computeOpening(OpeningJob& job);

// The opening in the making (at most one, on an idle-priority worker) and the one shown. Each is shown from the
// start of the frame open_surface_frames frames after it was started until the next one or the stroke's end.
class SurfaceOpening {
 public:
  // Starts an opening of `surface` along `cuts` due `frames` frames after the frame starting at t0 (computed when
  // due instead while the worker is still on one given up on).
  void start(double t0, int frames, std::vector<SweptSurface> cuts, const MetaballModel& spheres,
             std::shared_ptr<const CutSurfaceState> surface, const std::string& file);
  // At the start of the frame at t0: counts the frame (not the one it was started in) and says whether it is due.
  bool dueAt(double t0) { return job_ && t0 > job_->launched_at && --job_->frames_left <= 0; }
  // Shows the opening due now: the worker's, or, when the worker is not done within workerPatienceMs(), one
  // computed here from a copy of its inputs (the same result; the worker's copy is left to it). Returns the
  // milliseconds spent waiting or computing.
  double apply();
  // The stroke's end replaces whatever opening there is (one in the making finishes on its worker, unused).
  void discard() {
    job_.reset();
    shown_.reset();
  }

  bool inMaking() const { return bool(job_); }
  const OpenedSurface* shown() const { return shown_.get(); }
  long computedHere() const { return computed_here_; }     // openings computed on the frame's thread so far
  double lastWorkerMs() const { return last_worker_ms_; }  // the last applied opening's worker time

  // The frames left of the opening in the making with the guard's checkpoint (-1: none in the making). An opening
  // started in the retried frame keeps its count: that frame does not count it (t0 == launched_at).
  void saveCheckpoint() { saved_frames_left_ = job_ ? job_->frames_left : -1; }
  void restoreCheckpoint() {
    if (job_ && saved_frames_left_ >= 0) job_->frames_left = saved_frames_left_;
  }

 private:
  std::shared_ptr<OpeningJob> job_;  // shared with its worker's task: the task may be given up on
  std::unique_ptr<OpenedSurface> shown_;
  int saved_frames_left_ = -1;
  long computed_here_ = 0;
  double last_worker_ms_ = 0;
  BackgroundTask worker_{true};  // idle priority, as a stroke's end; declared last, joined first
};

}  // namespace inc::dissection
