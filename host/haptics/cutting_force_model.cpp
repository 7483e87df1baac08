// Cutting force model: validation of per-material thresholds and the per-tick update.
#include "host/haptics/cutting_force_model.h"

#include <cmath>

#include "host/compiled/material_checks.h"
#include "model/input_error.h"

namespace inc {

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
