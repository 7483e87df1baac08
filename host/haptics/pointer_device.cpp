// Mouse/keyboard device: pose from the UI thread, force back for display, through triple buffers.
#include "host/haptics/pointer_device.h"

#include <cmath>

#include "model/input_error.h"

namespace inc {

PointerDevice::PointerDevice(double max_force_n) : max_force_n_(max_force_n) {
  if (!(max_force_n > 0.0) || !std::isfinite(max_force_n))
    throw InputError("<pointer device>", "max_force_n", "must be > 0");
}

void PointerDevice::setPose(const Vec3d& position_m, const double q[4], std::uint32_t buttons) {
  DeviceSample& s = pose_.back();
  s.position_m = position_m;
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (int k = 0; k < 4; ++k) s.orientation[k] = n > 0.0 && std::isfinite(n) ? q[k] / n : (k == 0 ? 1.0 : 0.0);
  if (!isFinite(position_m)) s.position_m = Vec3d();
  s.buttons = buttons;
  pose_.publish();
}

Vec3d PointerDevice::displayForce() {
  force_.update();
  return force_.front();
}

DeviceSample PointerDevice::read(std::uint64_t, double t_s) {
  pose_.update();
  DeviceSample s = pose_.front();
  s.t_s = t_s;
  return s;
}

}  // namespace inc
