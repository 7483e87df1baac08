// The viewer's Material and Solver panels built from a loaded scene: knobs that edit a shared copy of the
// scene, and the factory that (re)builds the model from it.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "host/backends/backend_choice.h"
#include "host/scene/scene.h"
#include "viewer/sim_runner.h"

namespace inc::viewer {

struct SceneViewerSetup {
  std::shared_ptr<Scene> scene;   // the edited scene (the knobs write it, the factory reads it)
  ModelFactory factory;           // the scene's first model (createSceneModels) on the chosen backend
  std::vector<ViewerKnob> knobs;  // groups "Material" and "Solver"
  std::string backend_note;       // resolveBackend's note for the initial backend (fallback reason)
};

// Knobs (all but the time step rebuild the model from the edited scene; the state restarts from rest):
//   Material: "Young's modulus [Pa]" (log, E/100 .. 100 E), "Poisson ratio" (MLS scenes, 0 .. 0.49);
//   Solver:   "PBD iterations" (PBD scenes, 1 .. 100), "substeps (0 = auto)" (0 .. 64),
//             "time step [s]" (frame_dt, live, also written to the scene: 1e-4 .. 0.05 s),
//             "precision" (float32 | float64),
//             "backend" (cpu | cuda; cuda only in CUDA builds, a rebuild without a device is refused).
// `backend` overrides the scene's (the CLI's --backend). Throws InputError when the scene builds no model.
SceneViewerSetup makeSceneViewerSetup(const Scene& scene, std::optional<BackendKind> backend = std::nullopt);

}  // namespace inc::viewer
