// CPU (OpenMP) implementation of the PBD/XPBD backend: the same physics/pbd_block.h calls as the CUDA kernels.
#pragma once

#include <memory>

#include "host/pbd_model.h"

namespace inc::cpu {

template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdCpuBackend();

}  // namespace inc::cpu
