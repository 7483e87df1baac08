// A stroke's end in the making: its inputs and result, and the idle-priority workers that compute it.
#pragma once

#include <memory>

#include "base/background_task.h"
#include "host/assembly/pbd_builders.h"
#include "host/cut/cut_stroke_end.h"
#include "model/pbd_model.h"

namespace inc::dissection {

// A stroke's end in the making (the stroke still simulated meanwhile): the worker's inputs and result, and the
// frames left until it is applied.
template <typename T>
struct PendingStrokeEnd {
  StrokeEndInput input;
  StrokeEndResult result;
  PbdModel<T> pbd;  // the new PBD model, built on the worker
  int frames_left = 0;
  bool on_worker = false;  // started on the end workers (else computed when applied)
};

// A due stroke end's result and the PBD model built with it.
template <typename T>
struct StrokeEndOutcome {
  StrokeEndResult result;
  PbdModel<T> pbd;
  bool computed_here = false;  // the frame's thread computed it (the worker was given up on, or never started)
};

// A stroke's end and its surface split, at idle priority until the end is due (on two cores they would otherwise
// slow the frames simulated meanwhile 2.5-fold).
template <typename T>
class StrokeEndWorkers {
 public:
  // Starts computing `e` (its PBD model built with `opt`), unless the workers are still on an end given up on
  // (starved): then `e` is computed when due.
  void start(const std::shared_ptr<PendingStrokeEnd<T>>& e, MetaballPbdOptions opt);
  // The due end's result: the worker's, or, when it is not done within patience_ms (then at normal priority) or was
  // never started, computed on this thread with its split on `beside` (the worker's copy is left to it: it
  // finishes in the background). Rethrows what the worker threw.
  StrokeEndOutcome<T> collect(PendingStrokeEnd<T>& e, double patience_ms, BackgroundTask& beside,
                              const MetaballPbdOptions& opt);

 private:
  BackgroundTask split_worker_{true}, worker_{true};  // the worker's split beside its re-pack; joined first
};

}  // namespace inc::dissection
