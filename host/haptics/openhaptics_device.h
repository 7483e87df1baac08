// OpenHaptics (3D Systems HD API) device: a Phantom / Geomagic Touch. Compiled only when CMake finds the SDK.
#pragma once

#include <HD/hd.h>

#include <atomic>
#include <cstdint>
#include <string>

#include "host/haptics/haptic_device.h"
#include "host/haptics/triple_buffer.h"

namespace inc {

// Device frame (HD API: millimetres, x right, y up, z towards the user) to the scene frame (metres, z up):
// scene = offset_m + scale * M * (device_mm / 1000) with M = [[1, 0, 0], [0, 0, -1], [0, 1, 0]] (device y -> scene
// z, device z -> scene -y). Forces go back through M^T, unscaled (newtons stay newtons).
struct OpenHapticsMapping {
  double scale = 1.0;  // scene metres per device metre
  Vec3d offset_m;      // scene position of the device origin
};

// The HD servo thread (hdScheduleAsynchronous, the HD scheduler's rate) runs servo(): between hdBeginFrame and
// hdEndFrame it reads HD_CURRENT_POSITION, HD_CURRENT_TRANSFORM and HD_CURRENT_BUTTONS into a triple buffer and
// writes the newest force of the other triple buffer with hdSetDoublev(HD_CURRENT_FORCE). The haptic loop's
// read() / writeForce() only touch the triple buffers: neither thread ever waits for the other (the two 1 kHz
// loops are not phase locked: up to one servo period of extra latency). One device per process: the HD scheduler
// is process-wide. Untested here (no SDK, no device); docs/haptics.md.
class OpenHapticsDevice : public HapticDevice {
 public:
  // config_name: an OpenHaptics device configuration name, "" for HD_DEFAULT_DEVICE. Initialises the device,
  // reads HD_NOMINAL_MAX_FORCE, enables force output, schedules the servo callback and starts the scheduler.
  // Throws InputError("openhaptics", "device", reason with hdGetErrorString) when any step fails.
  OpenHapticsDevice(const std::string& config_name, const OpenHapticsMapping& mapping);
  ~OpenHapticsDevice() override;  // zero force, stop the scheduler, unschedule, disable the device
  OpenHapticsDevice(const OpenHapticsDevice&) = delete;
  OpenHapticsDevice& operator=(const OpenHapticsDevice&) = delete;

  DeviceSample read(std::uint64_t tick, double t_s) override;
  void writeForce(const Vec3d& force_n) override { force_.write(force_n); }
  double maxForce_n() const override { return max_force_n_; }
  std::string name() const override { return "openhaptics"; }
  std::uint64_t servoErrors() const { return servo_errors_.load(std::memory_order_relaxed); }

 private:
  static HDCallbackCode HDCALLBACK servo(void* self);
  void shutDown();
  OpenHapticsMapping map_;
  HHD device_ = HD_INVALID_HANDLE;
  HDSchedulerHandle callback_ = 0;
  bool scheduled_ = false, scheduler_started_ = false;
  double max_force_n_ = 0.0;
  TripleBuffer<DeviceSample> pose_;  // servo thread -> haptic loop
  TripleBuffer<Vec3d> force_;        // haptic loop -> servo thread
  std::atomic<std::uint64_t> servo_errors_{0};
};

}  // namespace inc
