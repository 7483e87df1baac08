// The models a scene switches on, built for the resolved backend.
#pragma once

#include <memory>
#include <vector>

#include "host/compiled/compiled_scene.h"
#include "host/sim/simulation_model.h"
#include "model/backend.h"

namespace inc {

// One model per switched-on model kind of `scene` (a cutting scene's organ is the dissection model itself).
std::vector<std::unique_ptr<SimulationModel>> createSceneModels(const CompiledScene& scene, BackendKind backend);

}  // namespace inc
