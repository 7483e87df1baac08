// CUDA implementation of the PBD/XPBD backend: batched kernels per block/colour, frame captured in a CUDA graph.
#pragma once

#include <memory>

#include "model/pbd_model.h"

namespace inc::cuda {

template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdCudaBackend();

}  // namespace inc::cuda
