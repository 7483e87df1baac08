// The one validation of a Material (material.youngs_modulus_pa, poisson_ratio, density_kg_m3, damping_per_s) and of
// the haptic cutting thresholds (material.cutting).
#include "host/compiled/material_checks.h"

#include <cmath>

#include "base/format_number.h"
#include "model/input_error.h"

namespace inc {

namespace {

std::string got(double v) { return " (got " + formatNumber(v) + ")"; }

}  // namespace

void validateYoungsModulus(double e, const std::string& file, const std::string& key) {
  // Written as !(e > 0) so that NaN fails too; infinity is refused separately (a reader never yields it).
  if (!(e > 0) || !std::isfinite(e)) throw InputError(file, key, "must be > 0" + got(e));
}

void validateMaterial(const Material& m, const std::string& file, const std::string& section) {
  const std::string prefix = section.empty() ? std::string() : section + ".";
  auto fail = [&](const char* key, const std::string& reason) { throw InputError(file, prefix + key, reason); };
  validateYoungsModulus(m.youngs_modulus_pa, file, prefix + "youngs_modulus_pa");
  const double nu = m.poisson_ratio;
  if (!(nu > -1 && nu < 0.5)) {
    fail("poisson_ratio", "must lie in the open interval (-1, 0.5)" + got(nu) +
                              "; 0.5 (incompressible) and -1 make the bulk or shear modulus infinite");
  }
  const double rho = m.density_kg_m3;
  if (!(rho > 0) || !std::isfinite(rho)) fail("density_kg_m3", "must be > 0" + got(rho));
  const double c = m.damping_per_s;
  if (!(c >= 0) || !std::isfinite(c)) fail("damping_per_s", "must be >= 0" + got(c));
}

void validateCutThresholds(const CutThresholds<double>& th, const std::string& file, const std::string& key) {
  auto check = [&](double v, bool ok, const char* name, const char* rule) {
    if (!std::isfinite(v) || !ok) throw InputError(file, key + "." + name, std::string(rule) + got(v));
  };
  check(th.press_n, th.press_n >= 0.0, "press_threshold_n", "F_p must be finite and >= 0 N");
  check(th.static_n, th.static_n > 0.0, "static_friction_n", "F_s must be finite and > 0 N");
  check(th.dynamic_n, th.dynamic_n > 0.0, "dynamic_friction_n", "F_d must be finite and > 0 N");
  check(th.friction_per_depth_n_per_m, th.friction_per_depth_n_per_m >= 0.0, "friction_n_per_m",
        "the friction slope must be finite and >= 0 N/m");
  if (!(th.dynamic_n < th.static_n))
    throw InputError(file, key + ".dynamic_friction_n",
                     "dynamic friction F_d must be below static friction F_s = " + formatNumber(th.static_n) +
                         " N (the hysteresis of eq. 16)" + got(th.dynamic_n));
}

}  // namespace inc
