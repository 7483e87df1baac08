// CPU (OpenMP) implementation of the PBD/XPBD backend: the same physics/pbd_block.h calls as the CUDA kernels.
#pragma once

#include <memory>

#include "model/pbd_model.h"

namespace inc::cpu {

template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdCpuBackend();

// Forces every constraint projection through pbd::projectConstraint, one constraint at a time (the shared scalar
// code of physics/pbd_block.h that the CUDA kernels run), where the CPU backend otherwise uses per-kind loops with
// vector forms (3-vector lanes for shape-matching frames and member passes and for the Laplacian, cluster lanes for
// rotation extractions: cpu_fallback/pbd_rotation_lanes.h, batches software-pipelined). The results are the same
// bits either way; tests compare the two. Process-wide; default false.
void setPbdReferenceLoop(bool reference);

}  // namespace inc::cpu
