// Cutting tool composition: contact anchor, elastic reaction, cut state machine, friction and the event queue.
#include "host/haptics/cutting_tool.h"

#include <cmath>

#include "model/input_error.h"

namespace inc {

CuttingTool::CuttingTool(Elastic elastic, const CutThresholds<double>& thresholds, const Vec3d& surface_point_m,
                         const Vec3d& unit_normal)
    : elastic_(std::move(elastic)), cut_(thresholds), surface_(surface_point_m), normal_(unit_normal) {
  if (!elastic_) throw InputError("<cutting tool>", "elastic", "no elastic force model");
  if (!isFinite(surface_point_m)) throw InputError("<cutting tool>", "surface_point_m", "must be finite");
  if (!(std::fabs(norm(unit_normal) - 1.0) <= 1e-6))
    throw InputError("<cutting tool>", "normal", "must be a unit vector");
}

ForceResult CuttingTool::tick(const ForceRequest& q) {
  const Vec3d p = q.sample.position_m;
  const Vec3d velocity = have_last_ ? (p - last_position_) * (1.0 / q.dt_s) : Vec3d();
  last_position_ = p;
  have_last_ = true;
  const double depth = -dot(p - surface_, normal_);  // > 0: below the surface plane
  const bool was_cutting = cut_.state() == CutState::kCutting;
  ForceResult r;
  if (depth > 0.0) {
    if (!in_contact_) anchor_ = p + normal_ * depth;  // where the blade entered, on the surface plane
    in_contact_ = true;
    // Cutting divides the tissue ahead of the blade: the anchor follows the tip along the surface.
    if (was_cutting) anchor_ = p + normal_ * depth;
    r = elastic_(TipContact{true, anchor_, p - anchor_});
  } else {
    in_contact_ = false;  // out of the tissue: no force (a linear model would pull the blade back in)
    (void)elastic_(TipContact{});
  }
  // The force the tool applies to the tissue (eq. 15): minus the elastic reaction, and while cutting minus
  // the friction it overcomes.
  const Vec3d friction =
      was_cutting ? cuttingFriction(velocity, normal_, depth, cut_.thresholds().friction_per_depth_n_per_m) : Vec3d();
  const CutForceOutput o = cut_.tick((r.force_n + friction) * -1.0, normal_, velocity, depth);
  r.force_n += o.friction_n;  // friction on the hand only while (still) cutting
  if (o.machine.start_cut || o.machine.stop_cut) {
    CutEvent e;
    e.start = o.machine.start_cut;
    e.tick = q.tick;
    e.t_s = q.t_s;
    e.position_m = p;
    for (int k = 0; k < 4; ++k) e.orientation[k] = q.sample.orientation[k];
    if (!events_.push(e)) ++dropped_;
  }
  return r;
}

}  // namespace inc
