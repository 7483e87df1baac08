// The dissection model's checks of its scene: the keys it needs, the cutting ranges, the scalpels' timing.
#pragma once

#include <string>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/compiled/compiled_scene.h"
#include "host/sim/dissection_stroke.h"
#include "model/mls_model.h"

namespace inc::dissection {

// The models the dissection needs and the cutting keys' ranges (programmatic scenes bypass the JSON loader: the
// same ranges, the same keys). Throws InputError naming the key.
void checkDissectionScene(const CompiledScene& scene);

// Several scalpels are several strokes, one after the other (a stroke is re-packed before the next begins):
// `strokes`, sorted by start, must not overlap in time.
void checkStrokesApart(const std::string& file, const std::vector<ScriptedStroke>& strokes);

// A fixed MLS substep count is checked against the nodal points' nominal stable step (the finest lattice,
// the material's P-wave speed; section 5.1 eq. 10): a step above it is refused as bad input. At run time the
// count is raised where the points' actual limit (densities, deformation, coupling springs) needs more.
void checkFixedMlsSubsteps(const CompiledScene& scene, const MetaballModel& spheres, const MlsMaterial& material);

}  // namespace inc::dissection
