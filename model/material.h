// The elastic material of a body: Young's modulus, Poisson's ratio, density and damping, in SI units.
#pragma once

namespace inc {

// One name for each quantity from the scene file to the solvers: the scene reads `material.<key>` into these
// fields (the field name is the key), and every builder and model takes a Material or one of its fields.
// Validated once, where it enters (host/compiled/material_checks.h).
struct Material {
  double youngs_modulus_pa = 3.0e3;  // Pa, > 0 (liver ~ 1-10 kPa)
  double poisson_ratio = 0.45;       // (-1, 0.5)
  double density_kg_m3 = 1060.0;     // kg/m^3, > 0 (rest density)
  double damping_per_s = 1.0;        // 1/s, mass-proportional damping coefficient, >= 0
};

}  // namespace inc
