// The MLS elastic solid as a SimulationModel built from a scene (sampling, fixed regions, material, solver).
#pragma once

#include <memory>

#include "host/compiled/compiled_scene.h"
#include "host/sim/simulation_model.h"
#include "model/backend.h"
#include "model/mls_model.h"

namespace inc {

// The scene's MLS solver settings without particles: source, support_factor, condition_limit, material (with
// mls.volume_preservation and volume_stiffness), gravity and safety. The dissection's nodal points take these too.
MlsBuildInput mlsSolverSettings(const CompiledScene& scene);

// The solver input a scene describes: particles sampled from scene.geometry (box/beam/sphere/ellipsoid, or a
// closed mesh scaled by mesh_scale), masses density * spacing^3, particles whose rest position lies in a
// `fixed` box held (Dirichlet), material, mls and solver settings. Throws InputError(scene.file, key, reason).
MlsBuildInput mlsBuildInputFromScene(const CompiledScene& scene);

// The MLS solid of `scene` on an already resolved backend (Cpu or Cuda, never Auto) in `precision`.
// Throws InputError for bad input, including a fixed substep count (solver.substeps) that is above the
// stable limit for the scene's frame_dt. advance() reports non-finite states (finite == false, stage
// "integrate" | "stress" | "forces", lowest bad particle) instead of throwing.
// FrameReport: stages integrate / stress / forces / reduce (ms, summed over substeps), kinetic, elastic
// (strain + volume penalty) and gravity potential energy, max displacement; counters: stable_dt_s (rest),
// current_stable_dt_s and stiffening (at the frame's end deformation, used to plan the next frame), regularised /
// few_neighbours / coplanar / collinear / ill_conditioned / isolated particles, min / mean neighbours, max_condition,
// grasped_particles. Tools: a "grasper" holds the particles within radius_m of its first keyframe (InputError if none)
// and carries them along its piecewise-linear path (prescribed displacement = tool position(t) - first position,
// reached at the end of each frame); "probe" and "scalpel" tools are left to the contact and cutting models.
std::unique_ptr<SimulationModel> makeMlsSimulation(const CompiledScene& scene, BackendKind resolved,
                                                   Precision precision);

}  // namespace inc
