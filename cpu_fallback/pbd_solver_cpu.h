// CPU (OpenMP) implementation of the PBD/XPBD backend: the same physics/pbd_block.h calls as the CUDA kernels.
#pragma once

#include <memory>

#include "host/pbd_model.h"

namespace inc::cpu {

template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdCpuBackend();

// Forces the scalar rotation extraction (pbd::extractRotations) where the CPU backend otherwise runs four clusters'
// extractions in SIMD lanes (cpu_fallback/pbd_rotation_lanes.h); the results are the same bits either way, and
// tests compare the two. Process-wide; default false.
void setPbdScalarRotations(bool scalar_only);

}  // namespace inc::cpu
