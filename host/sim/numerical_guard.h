// Detects non-finite values and energy blow-up after each frame, so nothing is ever silently wrong.
#pragma once

#include <string>

#include "host/sim/simulation_model.h"

namespace inc {

struct GuardVerdict {
  bool ok = true;
  std::string stage;           // where it went wrong ("forces", "energy", ...)
  std::int64_t particle = -1;  // which particle, when known
  std::string reason;
  // false: a retry at a smaller step cannot help (a frame the model refused for the frame budget needs more
  // substeps at half the step, not fewer).
  bool retryable = true;
};

class NumericalGuard {
 public:
  // energy_bound: total energy may not exceed energy_bound * reference. The reference is set from the
  // first good frame and never below `energy_scale_floor` (e.g. m |g| L of the scene), so a body that
  // starts at rest still gets a meaningful bound.
  NumericalGuard(double energy_bound, double energy_scale_floor);
  GuardVerdict check(const FrameReport& r);
  double reference() const { return reference_; }

 private:
  double bound_, floor_, reference_ = 0.0;
  bool have_reference_ = false;
};

}  // namespace inc
