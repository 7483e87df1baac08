// The metaball organ driven by PBD/XPBD as a SimulationModel built from a scene: sphere set, constraints, fixed
// regions, scripted tools.
#pragma once

#include <memory>
#include <string>

#include "host/assembly/metaball_model.h"
#include "host/compiled/compiled_scene.h"
#include "host/sim/simulation_model.h"
#include "model/backend.h"

namespace inc {

// The sphere set of the scene's organ. With pbd.target_spheres > 0: the sphere packer (packOrgan) fitted to
// the scene's closed surface (sceneSurfaceMesh), masses from power cells. Otherwise: a cubic lattice fill of the
// primitive (box, beam, sphere, ellipsoid; a closed mesh by winding number) at geometry.spacing, one sphere per lattice
// cell centre inside the body, radius 0.75 * spacing (face and edge neighbours overlap, corner ones do not),
// mass density * spacing^3 (so the total mass is the density times the sampled cell volume); spheres are
// linked when they overlap (|c_i - c_j| < r_i + r_j). Either way the sphere graph is then made one component per
// piece of the body (connectSphereGraph: stragglers linked inside the body, or dropped), so no sphere is left
// without a constraint; `fill_note`, when given, receives one line saying what was filled and repaired.
// Throws InputError(scene.file, key, reason).
MetaballModel buildSceneMetaballs(const CompiledScene& scene, std::string* fill_note = nullptr);

// The PBD metaball organ of `scene` on `backend` (Auto resolves like resolveBackend) in `precision`.
// Settings: pbd.iterations, pbd.xpbd, pbd.solver, pbd.stretch_compliance / laplacian_compliance (0: from
// material.youngs_modulus_pa), pbd.volume_preservation (power-cell radius adjustment near tools), material
// density and damping, solver.frame_dt / substeps (0: 4) / gravity, fixed boxes, tools (probe: contact
// capsule; grasper: catches spheres within its radius + one lattice spacing at its first keyframe, drags
// them along its path, releases at its last keyframe; scalpel: ignored here, the cutting model owns it).
// FrameReport: stages predict / constraints / collisions / velocities / volume (CPU wall time, CUDA
// events when profiling, else one "frame" stage), kinetic, elastic (stretch + Laplacian compliance energy
// sum C^2 / 2 alpha), gravity potential energy, max displacement; counters: residual_max_m,
// residual_rms_m, colors, iterations, substeps, grasped, volume_active, max_radius_ratio.
std::unique_ptr<SimulationModel> makeMetaballSimulation(const CompiledScene& scene, BackendKind backend,
                                                        Precision precision);

}  // namespace inc
