// Scene keys of the haptic cutting force model: material.cutting.{press_threshold_n, static_friction_n, ...}.
#include "host/haptics/cutting_scene.h"

#include "host/haptics/cutting_force_model.h"

namespace inc {

CutThresholds<double> readCutThresholds(const scene_json::ObjectReader& r) {
  r.allowOnly({"press_threshold_n", "static_friction_n", "dynamic_friction_n", "friction_n_per_m"});
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
