// Mouse/keyboard haptic device: the viewer's UI thread sets the tool pose, the haptic thread reads it.
#pragma once

#include "host/haptics/haptic_device.h"
#include "host/haptics/triple_buffer.h"

namespace inc {

// A device without force output: the viewer maps mouse drags (in the view plane) and keys (depth,
// buttons) to a pose with setPose(); the force the loop would render is published for drawing (an
// arrow) through displayForce(). Both directions go through lock-free triple buffers.
class PointerDevice : public HapticDevice {
 public:
  explicit PointerDevice(double max_force_n = 3.3);
  // UI thread.
  void setPose(const Vec3d& position_m, const double orientation_wxyz[4], std::uint32_t buttons);
  // Any one other thread (the viewer): newest force sent by the loop (N).
  Vec3d displayForce();
  // Haptic thread.
  DeviceSample read(std::uint64_t tick, double t_s) override;
  void writeForce(const Vec3d& force_n) override { force_.write(force_n); }
  double maxForce_n() const override { return max_force_n_; }
  std::string name() const override { return "pointer"; }

 private:
  double max_force_n_;
  TripleBuffer<DeviceSample> pose_;
  TripleBuffer<Vec3d> force_;
};

}  // namespace inc
