// The one validation of a Material and of the haptic cutting thresholds: the ranges docs/scene-format.md gives for
// material.*, with the scene's messages.
#pragma once

#include <string>

#include "model/material.h"
#include "physics/cutting_force.h"

namespace inc {

// Throws InputError(file, section + ".<key>", reason) for the first field out of range, in the order
// youngs_modulus_pa, poisson_ratio, density_kg_m3, damping_per_s (NaN and infinity are out of every range).
// The scene loader calls it with section "material"; builders that take a Material from elsewhere (tests, tools)
// call it with their caller's file and the same section, so a bad value reads the same wherever it is caught.
void validateMaterial(const Material& m, const std::string& file, const std::string& section = "material");

// The first of those checks alone, for a builder that takes only E (MetaballPbdOptions): InputError(file, key, ...).
void validateYoungsModulus(double youngs_modulus_pa, const std::string& file,
                           const std::string& key = "material.youngs_modulus_pa");

// Throws InputError(file, key + ".<scene key>", reason) unless F_p >= 0, F_s > 0, F_d > 0, friction slope >= 0,
// all finite, and F_d < F_s (scene keys: press_threshold_n, static_friction_n, dynamic_friction_n,
// friction_n_per_m; docs/scene-format.md).
void validateCutThresholds(const CutThresholds<double>& th, const std::string& file, const std::string& key);

}  // namespace inc
