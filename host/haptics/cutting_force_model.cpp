// Cutting force model: validation of per-material thresholds and the per-tick update.
#include "host/haptics/cutting_force_model.h"

#include <cmath>

#include "host/input_error.h"
#include "host/scene_json.h"

namespace inc {

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

CuttingForceModel::CuttingForceModel(const CutThresholds<double>& th, const std::string& file, const std::string& key)
    : th_(th) {
  validateCutThresholds(th_, file, key);
}

CutForceOutput CuttingForceModel::tick(const Vec3d& applied_force_n, const Vec3d& unit_normal,
                                       const Vec3d& velocity_m_s, double depth_m) {
  CutForceOutput out;
  out.split = decomposeForce(applied_force_n, unit_normal);
  const bool contact = depth_m > 0.0;
  machine_ = cutTransition(machine_, contact, norm(out.split.normal), norm(out.split.tangential), th_);
  out.machine = machine_;
  if (machine_.state == CutState::kCutting)
    out.friction_n = cuttingFriction(velocity_m_s, unit_normal, depth_m, th_.friction_per_depth_n_per_m);
  return out;
}

}  // namespace inc
