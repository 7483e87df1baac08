// Per-tick cutting force model for the haptic thread: eqs. 15-16 state machine plus depth-proportional friction.
#pragma once

#include <string>

#include "physics/cutting_force.h"

namespace inc {

struct CutForceOutput {
  CutMachine machine;
  ForceSplit<double> split;  // of the applied force (eq. 15)
  Vec3d friction_n;          // force of the tissue on the blade (newtons), add to the elastic reaction
};

// One material's model. Each tick: the force the tool applies to the tissue (N, e.g. minus the local
// model's reaction), the outward unit surface normal at the contact, the blade velocity (m/s) and the
// depth of the blade edge below the surface (m, <= 0 means no contact).
class CuttingForceModel {
 public:
  explicit CuttingForceModel(const CutThresholds<double>& th, const std::string& file = "<material>",
                             const std::string& key = "material.cutting");
  CutForceOutput tick(const Vec3d& applied_force_n, const Vec3d& unit_normal, const Vec3d& velocity_m_s,
                      double depth_m);
  CutState state() const { return machine_.state; }
  const CutThresholds<double>& thresholds() const { return th_; }
  void reset() { machine_ = CutMachine{}; }

 private:
  CutThresholds<double> th_;
  CutMachine machine_;
};

}  // namespace inc
