// The MLS solver on the GPU: the passes of physics/mls_passes.h as CUDA kernels, state resident on the device.
#pragma once

#include <memory>

#include "model/mls_model.h"
#include "model/mls_solver.h"

namespace inc::cuda {

// Uploads the model once; every substep runs on the device (drift, stress, force + kick kernels) and the
// host sees one small download per frame (the frame reductions). Throws std::runtime_error on CUDA errors.
std::unique_ptr<MlsSolver> makeMlsSolverCuda(MlsModel<float> model);
std::unique_ptr<MlsSolver> makeMlsSolverCuda(MlsModel<double> model);

}  // namespace inc::cuda
