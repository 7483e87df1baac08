// Scene keys of the haptic cutting force model (material.cutting): reading (the ranges are checked by
// validateCutThresholds, host/compiled/material_checks.h; writing is the key table's).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "host/scene/scene_json.h"
#include "physics/cutting_force.h"

namespace inc {

// Reads material.cutting (docs/scene-format.md): press_threshold_n (F_p, >= 0), static_friction_n (F_s, > 0),
// dynamic_friction_n (F_d, > 0 and < F_s), friction_n_per_m (>= 0); absent keys keep the defaults of
// CutThresholds. Throws InputError(file, "material.cutting.<key>", reason) for a non-number, NaN, a
// negative value or F_d >= F_s.
CutThresholds<double> readCutThresholds(const scene_json::ObjectReader& cutting);

}  // namespace inc
