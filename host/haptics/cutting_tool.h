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
  Vec3d position_m;                              // blade tip when the decision was taken
  double orientation[4] = {1.0, 0.0, 0.0, 0.0};  // the device's orientation then (w, x, y, z)
};

// What a tool tells its elastic model every tick (haptic thread).
struct TipContact {
  bool in_contact = false;  // the tip is below the tissue surface plane
  Vec3d anchor_m;           // in contact: the tissue point the elastic model measures the tip from
  Vec3d displacement_m;     // in contact: tip minus anchor
};

// Composes an elastic force model (the local model's force on the hand for a tip displacement from the
// tissue point under the blade, e.g. a TipStiffness or a GlobalOrganModel contact) with the cutting model (eqs. 15-16)
// on the tissue surface plane through `surface_point_m` with outward `unit_normal`. Each tick:
// - depth = how far the tip is below the plane; no depth, no contact: zero force, state idle.
// - the anchor (the tissue point the elastic model measures the tip from) is set where the tip enters;
//   while pressing or stopped it stays (the tissue sticks to the blade); while cutting it follows the tip
//   along the surface (the tissue ahead is divided, so no tangential elastic drag builds up).
// - eq. 15 split of the force the tool applies to the tissue: minus the elastic reaction, plus, while
//   cutting, minus the friction k * depth against the blade's motion (the paper's rendered force during a
//   cut). eq. 16: enter when |f_n| > F_p, start when |f_t| > F_s (the elastic drag from the anchor), stop
//   when |f_t| < F_d (the blade slows to a halt or rises until k * depth < F_d).
// - the force on the hand: the elastic reaction plus the friction while cutting.
// Start/stop decisions are pushed to events() for the simulation thread's cutting pipeline (never
// blocking; a full queue drops the event and counts it).
class CuttingTool {
 public:
  // Called every tick, out of contact too (a coupled global model learns there that the contact ended); out of
  // contact the tool renders no force whatever it returns.
  using Elastic = std::function<ForceResult(const TipContact& contact)>;
  CuttingTool(Elastic elastic, const CutThresholds<double>& thresholds, const Vec3d& surface_point_m,
              const Vec3d& unit_normal);
  ForceResult tick(const ForceRequest& request);
  SpscRing<CutEvent, 256>& events() { return events_; }
  CutState state() const { return cut_.state(); }
  const Vec3d& anchor() const { return anchor_; }
  std::uint64_t droppedEvents() const { return dropped_; }

 private:
  Elastic elastic_;
  CuttingForceModel cut_;
  Vec3d surface_, normal_, last_position_, anchor_;
  bool have_last_ = false, in_contact_ = false;
  SpscRing<CutEvent, 256> events_;
  std::uint64_t dropped_ = 0;
};

}  // namespace inc
