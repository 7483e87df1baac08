// CUDA tearing step: yield detection, independent set, CUB prefix sum + stream compaction, particle creation and
// triangle rebuild on the device.
#pragma once

#include <memory>

#include "model/tear_step.h"
#include "model/tearing_sheet.h"

namespace inc::cuda {

// The tearing step as a TearStepBackend (device buffers kept between steps).
template <typename T>
std::unique_ptr<TearStepBackend<T>> makeTearStepCuda();

// One step with the same phases and results as cpu::tearStepCpu (for the parity test). Leaves the adjacency
// stale: call s.rebuildTopology() afterwards when splits > 0.
template <typename T>
TearStepStats tearStepCuda(TearSheet<T>& s, const TearParams<T>& p, TearCandidates<T>* out = nullptr);

}  // namespace inc::cuda
