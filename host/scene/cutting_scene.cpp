// Scene keys of the haptic cutting force model: material.cutting.{press_threshold_n, static_friction_n, ...}.
#include "host/scene/cutting_scene.h"

#include <cmath>

#include "host/compiled/material_checks.h"
#include "host/scene/scene_keys.h"
#include "model/input_error.h"

namespace inc {

CutThresholds<double> readCutThresholds(const scene_json::ObjectReader& r) {
  r.allowOnly(sceneKeysUnder("material.cutting"));
  CutThresholds<double> th;
  // number() already refuses NaN / infinity and non-numbers with the key path; ranges are checked below
  // in one place (validateCutThresholds) so the haptic code and the scene agree on them.
  th.press_n = r.number("press_threshold_n", th.press_n);
  th.static_n = r.number("static_friction_n", th.static_n);
  th.dynamic_n = r.number("dynamic_friction_n", th.dynamic_n);
  th.friction_per_depth_n_per_m = r.number("friction_n_per_m", th.friction_per_depth_n_per_m);
  validateCutThresholds(th, r.file(), r.path());
  return th;
}

nlohmann::ordered_json cutThresholdsJson(const CutThresholds<double>& th) {
  return nlohmann::ordered_json{{"press_threshold_n", th.press_n},
                                {"static_friction_n", th.static_n},
                                {"dynamic_friction_n", th.dynamic_n},
                                {"friction_n_per_m", th.friction_per_depth_n_per_m}};
}

}  // namespace inc
