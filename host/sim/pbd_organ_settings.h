// The PBD organ's step parameters and model build options, translated from the compiled scene in one place: the
// metaball organ and the dissection (whose organ is the same PBD model) both run on them.
#pragma once

#include "host/assembly/pbd_builders.h"
#include "host/compiled/compiled_scene.h"
#include "model/pbd_model.h"

namespace inc {

// pbd.solver, pbd.iterations, pbd.chebyshev_rho, pbd.xpbd, pbd.volume_preservation, solver.gravity_m_s2 and
// material.damping_per_s as the solvers' PbdStepParams; the volume constraint's reach is two lattice spacings. Throws
// InputError(scene.file, "pbd.solver" | "pbd.chebyshev_rho", reason) for a solver it does not know or an
// acceleration that solver cannot take.
template <typename T>
PbdStepParams<T> pbdOrganParams(const CompiledScene& scene);

// The build options every PBD organ model of the scene shares: E, the compliances, the fixed boxes, the colliders,
// the volume samples and the file its errors name. The caller adds what depends on its organ (surface depth,
// reused volumes, colouring).
MetaballPbdOptions pbdOrganOptions(const CompiledScene& scene);

}  // namespace inc
