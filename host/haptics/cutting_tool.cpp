// Cutting tool composition: elastic reaction, cut state machine, friction and the event queue.
#include "host/haptics/cutting_tool.h"

#include <cmath>

#include "host/input_error.h"

namespace inc {

CuttingTool::CuttingTool(Elastic elastic, const CutThresholds<double>& thresholds, const Vec3d& contact_point_m,
                         const Vec3d& unit_normal)
    : elastic_(std::move(elastic)), cut_(thresholds), contact_(contact_point_m), normal_(unit_normal) {
  if (!elastic_) throw InputError("<cutting tool>", "elastic", "no elastic force model");
  if (std::fabs(norm(unit_normal) - 1.0) > 1e-6) throw InputError("<cutting tool>", "normal", "must be a unit vector");
}

ForceResult CuttingTool::tick(const ForceRequest& q) {
  const Vec3d p = q.sample.position_m;
  const Vec3d velocity = have_last_ ? (p - last_position_) * (1.0 / q.dt_s) : Vec3d();
  last_position_ = p;
  have_last_ = true;
  ForceResult r = elastic_(p - contact_);
  const double depth = -dot(p - contact_, normal_);  // > 0: below the surface plane
  const CutForceOutput o = cut_.tick(-r.force_n, normal_, velocity, depth);  // the tool pushes with -reaction
  r.force_n += o.friction_n;
  if (o.machine.start_cut || o.machine.stop_cut) {
    CutEvent e;
    e.start = o.machine.start_cut;
    e.tick = q.tick;
    e.t_s = q.t_s;
    e.position_m = p;
    if (!events_.push(e)) ++dropped_;
  }
  return r;
}

}  // namespace inc
