// The tearing sheet as a SimulationModel built from a scene (skin geometry, material, PBD settings, grasper and scalpel
// tools).
#pragma once

#include <memory>

#include "host/compiled/compiled_scene.h"
#include "host/sim/simulation_model.h"
#include "model/backend.h"
#include "model/tearing_sheet.h"

namespace inc {

// What a scene says about the tearing sheet (docs/tearing.md, "Scenes"):
//  geometry box  -> flat sheet of size_m.x by size_m.y in the plane z = center.z, spacing_m apart;
//  geometry beam -> open tube (a leg's skin) along x: length size_m.x, radius size_m.y / 2;
//  geometry mesh -> the mesh's own triangles (scaled by mesh_scale) as the skin;
//  tearing: criterion, k_pa (0: material.youngs_modulus_pa), tau_f_pa (0: 0.1 k), break_strain,
//  random_range, seed (the debris), regions (k and tau_f per box); material: area density density *
//  spacing; damping_per_s the PBD damping; pbd: iterations, xpbd, solver, stretch_compliance; fixed boxes hold
//  particles; tools: "grasper" grabs the particles within radius_m of its blade (position .. position + direction *
//  length_m) at t = 0 and moves them along its path; "scalpel" removes the tissue within radius_m of its blade every
//  frame between its first and last keyframe (the criterion tears around it).
struct TearingSceneSetup {
  TearSheet<double> sheet;
  TearParams<double> tear;
  TearModelOptions model;
  double damping_per_s = 1.0;  // Material::damping_per_s: the PBD solve's damping
  int iterations = 10;
  bool xpbd = true;
  std::string solver = "jacobi";
};
TearingSceneSetup tearingSetupFromScene(const CompiledScene& scene);

// The tearing sheet of `scene` on a resolved backend (Cpu or Cuda) in `precision`. Throws InputError.
// FrameReport stages: solve, tear, rebuild (ms); counters: splits, yielding, deferred, removed, particles,
// triangles.
std::unique_ptr<SimulationModel> makeTearingSimulation(const CompiledScene& scene, BackendKind backend,
                                                       Precision precision);

}  // namespace inc
