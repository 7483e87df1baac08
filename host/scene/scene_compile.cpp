// compileScene: the one place where a Scene's model inputs are handed to the layers below the application.
#include "host/scene/scene_compile.h"

namespace inc {

CompiledScene compileScene(const Scene& scene) {
  CompiledScene c;
  c.file = scene.file;
  c.geometry = scene.geometry;
  c.material = scene.material;
  c.cut_thresholds = scene.cut_thresholds;
  c.models = scene.models;
  c.mls = scene.mls;
  c.pbd = scene.pbd;
  c.solver = scene.solver;
  c.fixed = scene.fixed;
  c.tools = scene.tools;
  c.colliders = scene.colliders;
  c.tearing = scene.tearing;
  c.cutting = scene.cutting;
  c.haptics = scene.haptics;
  return c;
}

}  // namespace inc
