// The scene description: what a JSON scene file says, validated, in SI units (see docs/scene-format.md). Read by
// the loader, the writer and the application only: compileScene (host/scene/scene_compile.h) turns it into the
// CompiledScene every layer below the application is built from.
#pragma once

#include <string>
#include <vector>

#include "host/compiled/model_specs.h"
#include "model/material.h"
#include "physics/cutting_force.h"

namespace inc {

// What `incision run` writes (`output`): an application setting, not part of the compiled scene.
struct OutputSpec {
  int every_frames = 0;  // 0: final state only; N: also every N frames
  bool particles_ply = true;
  bool mesh_obj = true;
  bool vtk = false;  // legacy VTK point/mesh files for ParaView
  bool metrics_csv = true;
};

struct Scene {
  std::string file;  // where it came from ("<embedded:name>" for built-in scenes)
  std::string name;
  std::string description;
  double duration = 1.0;  // s, default run length when neither --steps nor --seconds is given
  GeometrySpec geometry;
  Material material;                     // material.{youngs_modulus_pa, poisson_ratio, density_kg_m3, damping_per_s}
  CutThresholds<double> cut_thresholds;  // material.cutting: the haptic cutting force model (eqs. 15-16): F_p, F_s,
                                         // F_d (N), friction (N/m); a haptic setting, so not part of Material
  ModelsSpec models;
  MlsSpec mls;
  PbdSpec pbd;
  SolverSpec solver;
  std::vector<FixedRegion> fixed;
  std::vector<ToolSpec> tools;
  std::vector<ColliderSpec> colliders;
  OutputSpec output;
  TearingSpec tearing;
  CuttingSpec cutting;
  HapticsSpec haptics;
};

}  // namespace inc