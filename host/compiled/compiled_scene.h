// The compiled scene: what every layer below the application is built from (the models, their backends, the
// topology events, haptics). The Scene (host/scene/scene.h) derives from it and adds the application settings
// (name, description, run length, output); compileScene (host/scene/scene_compile.h) hands on this part alone.
#pragma once

#include <string>
#include <vector>

#include "host/compiled/model_specs.h"
#include "model/material.h"
#include "physics/cutting_force.h"

namespace inc {

struct CompiledScene {
  std::string file;                      // the scene file, named by every InputError a build raises
                                         // ("<embedded:name>" for a built-in scene)
  GeometrySpec geometry;                 // the organ's shape and sampling
  Material material;                     // the one material of every model (model/material.h)
  CutThresholds<double> cut_thresholds;  // the haptic cutting force model (eqs. 15-16)
  ModelsSpec models;                     // which models to build
  MlsSpec mls;
  PbdSpec pbd;
  SolverSpec solver;                    // frame step, substeps, precision, backend, gravity, energy guard
  std::vector<FixedRegion> fixed;       // Dirichlet boxes
  std::vector<ToolSpec> tools;          // scripted probes, graspers and scalpels
  std::vector<ColliderSpec> colliders;  // static planes and boxes
  TearingSpec tearing;
  CuttingSpec cutting;
  HapticsSpec haptics;
};

}  // namespace inc
