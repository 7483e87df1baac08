// A conversion in the making: spheres the blade enters becoming nodal points, and the stroke's next PBD model.
#pragma once

#include <cstdint>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/assembly/pbd_builders.h"
#include "host/cut/cut_nodal_region.h"
#include "host/cut/cut_swept_surface.h"
#include "host/sim/dissection_stroke.h"
#include "model/pbd_model.h"

namespace inc::dissection {

// The stroke's next PBD model for given sphere roles, built (rest configuration only: a worker may build it while
// the frame goes on with the current model).
template <typename T>
struct StrokePbdPlan {
  MetaballModel spheres;
  std::vector<std::int32_t> base_to_pbd, pbd_to_base;
  PbdModel<T> built;
  double build_ms = 0;
  bool preloaded = false;  // `built` is in the spare backend already (DissectionSimulation::preloadStrokePbd)
};

// Plans the PBD model of stroke `a` after its spheres take `roles`, built with `opt` (the scene's options; the
// rest cell volumes and contact insets of the spheres that keep them are filled in from the base model's).
template <typename T>
StrokePbdPlan<T> planStrokePbd(const ActiveStroke& a, const std::vector<SphereRole>& roles, MetaballPbdOptions opt);

// A conversion in the making (cutting.conversion_delay_frames 1), or being applied: the strip, the region's
// update and the stroke's next PBD model, prepared on the conversion workers.
template <typename T>
struct PendingConversion {
  double launched_at = 0;  // s: the start of the frame the blade entered in (applied at a later frame's start)
  SweptSurface fresh;      // the new strip alone
  bool cut = false;        // spheres were cut: `pbd` is the stroke's next PBD model
  NodalUpdate mls;
  StrokePbdPlan<T> pbd;
  double mls_prepare_ms = 0, pbd_prepare_ms = 0;
};

}  // namespace inc::dissection
