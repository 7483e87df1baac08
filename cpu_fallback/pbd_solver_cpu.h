// CPU (OpenMP) implementation of the PBD/XPBD backend: the same physics/pbd_block.h calls as the CUDA kernels.
#pragma once

#include <memory>

#include "host/pbd_model.h"

namespace inc::cpu {

template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdCpuBackend();

// Forces shape matching through the shared scalar code (pbd::projectShapeMatchingClusters in physics/pbd_block.h,
// the formulas the CUDA kernels run) where the CPU backend otherwise uses its vector forms (3-vector lanes for frames
// and member passes, cluster lanes for rotation extractions: cpu_fallback/pbd_rotation_lanes.h). The results are the
// same bits either way; tests compare the two. Process-wide; default false.
void setPbdScalarShapeMatching(bool scalar_only);

}  // namespace inc::cpu
