// Builds the models a scene switches on, and nothing else (a scene pays only for what it uses).
#include "host/input_error.h"
#include "host/runner.h"

namespace inc {

std::vector<std::unique_ptr<SimulationModel>> createSceneModels(const Scene& scene, BackendKind backend) {
  std::vector<std::unique_ptr<SimulationModel>> models;
  (void)backend;
  if (scene.models.mls)
    throw InputError(scene.file, "models.mls", "the MLS model is not built into this version");
  return models;
}

}  // namespace inc
