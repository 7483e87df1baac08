// The compile boundary: a validated Scene becomes the CompiledScene the models, backends, topology events and
// haptics are built from (host/compiled/compiled_scene.h). The application calls it once per run or rebuild.
#pragma once

#include "host/compiled/compiled_scene.h"
#include "host/scene/scene.h"

namespace inc {

// The scene's model inputs (its CompiledScene part), without what only the application reads (name, description,
// duration, output).
// The loader has validated `scene`; the builders check again what a scene built in code could get wrong.
CompiledScene compileScene(const Scene& scene);

}  // namespace inc
