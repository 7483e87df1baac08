// NaN / Inf / energy blow-up checks on the per-frame reductions (cheap: no per-particle host work).
#include "host/sim/numerical_guard.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace inc {

NumericalGuard::NumericalGuard(double energy_bound, double energy_scale_floor)
    : bound_(energy_bound), floor_(std::max(energy_scale_floor, 1e-30)) {}

GuardVerdict NumericalGuard::check(const FrameReport& r) {
  GuardVerdict v;
  const double total = r.kinetic_energy + r.elastic_energy + r.potential_energy;
  if (!r.finite) {
    v.ok = false;
    v.stage = r.failure_stage.empty() ? "unknown" : r.failure_stage;
    v.particle = r.failure_particle;
    v.reason = r.failure_reason.empty() ? "non-finite value" : r.failure_reason;
    v.retryable = !r.refused;
    return v;
  }
  if (!std::isfinite(total) || !std::isfinite(r.max_displacement)) {
    v.ok = false;
    v.stage = "energy";
    v.reason = "non-finite energy or displacement";
    return v;
  }
  // Kinetic plus elastic energy measures how far the body is from a sane state; gravity potential can
  // legitimately be large and negative, so it only enters through the reference scale.
  const double excess = r.kinetic_energy + r.elastic_energy;
  // The first frame is judged against the scene's energy scale alone (it may itself be the one that
  // explodes); later frames against the larger of that scale and the first frame's energy.
  const double reference = have_reference_ ? reference_ : floor_;
  if (excess > bound_ * reference) {
    std::ostringstream s;
    s << "energy blow-up: kinetic + elastic = " << excess << " J exceeds " << bound_ << " x reference " << reference
      << " J";
    v.ok = false;
    v.stage = "energy";
    v.reason = s.str();
    return v;
  }
  if (!have_reference_) {
    reference_ = std::max(floor_, excess);
    have_reference_ = true;
  }
  return v;
}

}  // namespace inc
