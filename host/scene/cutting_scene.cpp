// Scene keys of the haptic cutting force model: material.cutting.{press_threshold_n, static_friction_n, ...}.
#include "host/scene/cutting_scene.h"

#include <cmath>

#include "host/scene/scene_fields.h"
#include "host/scene/scene_keys.h"
#include "model/input_error.h"

namespace inc {

CutThresholds<double> readCutThresholds(const scene_json::ObjectReader& r) {
  r.allowOnly(sceneKeysUnder("material.cutting"));
  CutThresholds<double> th;
  // The table's reads refuse NaN / infinity and non-numbers with the key path; ranges are checked below
  // in one place (validateCutThresholds) so the haptic code and the scene agree on them.
  readSceneKeys(r, "material.cutting", th);
  validateCutThresholds(th, r.file(), r.path());
  return th;
}

void validateCutThresholds(const CutThresholds<double>& th, const std::string& file, const std::string& key) {
  auto got = [](double v) { return " (got " + scene_json::formatNumber(v) + ")"; };
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
                     "dynamic friction F_d must be below static friction F_s = " + scene_json::formatNumber(th.static_n) +
                         " N (the hysteresis of eq. 16)" + got(th.dynamic_n));
}

}  // namespace inc
