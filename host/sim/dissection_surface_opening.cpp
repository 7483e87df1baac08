// The surface opened during a stroke: the opening's split and binding on an idle-priority worker, and its display.
#include "host/sim/dissection_surface_opening.h"

#include <algorithm>
#include <chrono>
#include <exception>
#include <utility>

#include "base/elapsed_ms.h"
#include "host/cut/cut_stroke_end.h"
#include "host/sim/dissection_stroke.h"

namespace inc::dissection {

void computeOpening(OpeningJob& job) {
  const auto c0 = std::chrono::steady_clock::now();
  try {
    job.state = *job.surface;
    job.split = applySurfaceCut(job.state, job.cuts.back()).split;
    if (job.split) {
      const int k = std::min<int>(4, int(job.spheres.size()));
      job.skin = bindSkinAcrossCuts(job.state, job.spheres, job.cuts, k, job.file);
    }
  } catch (const std::exception&) {
    // A sweep the split refuses (or any failure of it): nothing new to show. Display only, so it never ends the
    // run; the stroke's end splits for good and reports.
    job.split = false;
  }
  job.worker_ms = msSince(c0);
}

void SurfaceOpening::start(double t0, int frames, std::vector<SweptSurface> cuts, const MetaballModel& spheres,
                           std::shared_ptr<const CutSurfaceState> surface, const std::string& file) {
  auto job = std::make_shared<OpeningJob>();
  job->launched_at = t0;
  job->frames_left = frames;
  job->cuts = std::move(cuts);
  job->spheres = spheres;
  job->surface = std::move(surface);
  job->file = file;
  job_ = job;
  if (!worker_.done()) return;  // still on an opening given up on (starved): this one is computed when due
  job->on_worker = true;
  worker_.start([job, gate = idleWorkerGate()] {  // the task holds its job: it may be given up on
    if (gate) gate();
    computeOpening(*job);
  });
}

double SurfaceOpening::apply() {
  const auto c0 = std::chrono::steady_clock::now();
  std::shared_ptr<OpeningJob> job = std::move(job_);
  bool here = !job->on_worker;
  if (job->on_worker && !worker_.done()) {
    worker_.boost();
    here = !worker_.waitFor(workerPatienceMs(last_worker_ms_));
  }
  if (here) {  // computed here from a copy of its inputs: a worker given up on still reads the job's
    auto own = std::make_shared<OpeningJob>();
    own->cuts = job->cuts;
    own->spheres = job->spheres;
    own->surface = job->surface;
    own->file = job->file;
    computeOpening(*own);
    job = own;
    ++computed_here_;
  }
  const double waited_ms = msSince(c0);
  last_worker_ms_ = job->worker_ms;
  if (!job->split) return waited_ms;
  auto o = std::make_unique<OpenedSurface>();
  o->mesh = job->state.mesh;
  o->wall = job->state.wall;
  o->skin = skinSlots(std::move(job->skin));
  shown_ = std::move(o);
  return waited_ms;
}

}  // namespace inc::dissection
