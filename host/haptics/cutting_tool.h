// A cutting tool on the haptic thread: elastic reaction + eqs. 15-16 cut decisions + friction, events out.
#pragma once

#include <cstdint>
#include <functional>

#include "host/haptics/cutting_force_model.h"
#include "host/haptics/haptic_loop.h"
#include "host/haptics/spsc_ring.h"

namespace inc {

struct CutEvent {
  bool start = false;  // true: cutting began; false: cutting ended
  std::uint64_t tick = 0;
  double t_s = 0.0;
  Vec3d position_m;    // blade tip when the decision was taken
};

// Composes an elastic force model (e.g. HybridHapticModel::localTick on the displacement from the
// contact point) with the cutting model. Each tick: the tool applies -f_elastic to the tissue (eq. 15
// split on the contact normal), depth = how far the tip is below the surface plane, velocity from the
// last tick; while cutting, the friction is added to the force on the hand. Start/stop decisions are
// pushed to events() for the simulation thread's cutting pipeline (never blocking; a full queue drops
// the event and counts it).
class CuttingTool {
 public:
  using Elastic = std::function<ForceResult(const Vec3d& tip_displacement_m)>;
  CuttingTool(Elastic elastic, const CutThresholds<double>& thresholds, const Vec3d& contact_point_m,
              const Vec3d& unit_normal);
  ForceResult tick(const ForceRequest& request);
  SpscRing<CutEvent, 256>& events() { return events_; }
  CutState state() const { return cut_.state(); }
  std::uint64_t droppedEvents() const { return dropped_; }

 private:
  Elastic elastic_;
  CuttingForceModel cut_;
  Vec3d contact_, normal_, last_position_;
  bool have_last_ = false;
  SpscRing<CutEvent, 256> events_;
  std::uint64_t dropped_ = 0;
};

}  // namespace inc
