// compileScene: the one place where a Scene's model inputs are handed to the layers below the application.
#include "host/scene/scene_compile.h"

namespace inc {

CompiledScene compileScene(const Scene& scene) { return scene; }  // the model inputs: the base the Scene extends

}  // namespace inc
