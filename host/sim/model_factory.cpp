// Builds the models a scene switches on, and nothing else (a scene pays only for what it uses).
#include "host/sim/model_factory.h"

#include "host/sim/dissection_simulation.h"
#include "host/sim/metaball_simulation.h"
#include "host/sim/mls_simulation.h"
#include "host/sim/tearing_simulation.h"

namespace inc {

std::vector<std::unique_ptr<SimulationModel>> createSceneModels(const CompiledScene& scene, BackendKind backend) {
  std::vector<std::unique_ptr<SimulationModel>> models;
  if (scene.models.mls) models.push_back(makeMlsSimulation(scene, backend, scene.solver.precision));
  // A cutting scene's organ is the PBD metaball organ itself: build one or the other, never both.
  if (scene.models.cutting)
    models.push_back(makeDissectionSimulation(scene, backend, scene.solver.precision));
  else if (scene.models.pbd_metaballs)
    models.push_back(makeMetaballSimulation(scene, backend, scene.solver.precision));
  if (scene.models.tearing) models.push_back(makeTearingSimulation(scene, backend, scene.solver.precision));
  return models;
}

}  // namespace inc
