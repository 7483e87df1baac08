// OpenHaptics device: HD servo callback copying pose in and force out through triple buffers; frame mapping.
#include "host/haptics/openhaptics_device.h"

#include <chrono>
#include <cmath>
#include <thread>

#include "model/input_error.h"

namespace inc {

namespace {

// Throws with the newest HD error, if any.
void throwOnHdError(const std::string& what) {
  const HDErrorInfo e = hdGetError();
  if (HD_DEVICE_ERROR(e)) {
    const HDstring text = hdGetErrorString(e.errorCode);
    throw InputError("openhaptics", "device",
                     what + " failed: " + (text ? text : "unknown HD error") + " (HD error " +
                         std::to_string(e.errorCode) + ", internal " + std::to_string(e.internalErrorCode) + ")");
  }
}

// Device frame -> scene frame rotation M (see OpenHapticsMapping).
Vec3d deviceToScene(const double v[3]) { return Vec3d{v[0], -v[2], v[1]}; }
Vec3d sceneToDevice(const Vec3d& v) { return Vec3d{v.x, v.z, -v.y}; }

// Unit quaternion (w, x, y, z) of a rotation matrix r[row][col] (Shepperd's method: the largest of the four
// candidate divisors, so no cancellation).
void quaternionOf(const double r[3][3], double q[4]) {
  const double tr = r[0][0] + r[1][1] + r[2][2];
  if (tr > 0.0) {
    const double s = 2.0 * std::sqrt(1.0 + tr);
    q[0] = 0.25 * s;
    q[1] = (r[2][1] - r[1][2]) / s;
    q[2] = (r[0][2] - r[2][0]) / s;
    q[3] = (r[1][0] - r[0][1]) / s;
  } else if (r[0][0] > r[1][1] && r[0][0] > r[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]);
    q[0] = (r[2][1] - r[1][2]) / s;
    q[1] = 0.25 * s;
    q[2] = (r[0][1] + r[1][0]) / s;
    q[3] = (r[0][2] + r[2][0]) / s;
  } else if (r[1][1] > r[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]);
    q[0] = (r[0][2] - r[2][0]) / s;
    q[1] = (r[0][1] + r[1][0]) / s;
    q[2] = 0.25 * s;
    q[3] = (r[1][2] + r[2][1]) / s;
  } else {
    const double s = 2.0 * std::sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]);
    q[0] = (r[1][0] - r[0][1]) / s;
    q[1] = (r[0][2] + r[2][0]) / s;
    q[2] = (r[1][2] + r[2][1]) / s;
    q[3] = 0.25 * s;
  }
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (int k = 0; k < 4; ++k) q[k] = n > 0.0 ? q[k] / n : (k == 0 ? 1.0 : 0.0);
}

}  // namespace

OpenHapticsDevice::OpenHapticsDevice(const std::string& config_name, const OpenHapticsMapping& mapping)
    : map_(mapping) {
  if (!(map_.scale > 0.0) || !std::isfinite(map_.scale))
    throw InputError("openhaptics", "workspace_scale", "must be > 0");
  DeviceSample origin;
  origin.position_m = map_.offset_m;
  pose_.reset(origin);
  force_.reset(Vec3d{});
  const HDstring config = config_name.empty() ? nullptr : config_name.c_str();  // nullptr: HD_DEFAULT_DEVICE
  device_ = hdInitDevice(config);
  throwOnHdError("hdInitDevice(\"" + config_name + "\")");
  try {
    HDdouble max_force = 0.0;
    hdGetDoublev(HD_NOMINAL_MAX_FORCE, &max_force);
    throwOnHdError("hdGetDoublev(HD_NOMINAL_MAX_FORCE)");
    if (!(max_force > 0.0))
      throw InputError("openhaptics", "device", "the device reports no force output (HD_NOMINAL_MAX_FORCE <= 0)");
    max_force_n_ = max_force;
    hdEnable(HD_FORCE_OUTPUT);
    throwOnHdError("hdEnable(HD_FORCE_OUTPUT)");
    callback_ = hdScheduleAsynchronous(&OpenHapticsDevice::servo, this, HD_MAX_SCHEDULER_PRIORITY);
    throwOnHdError("hdScheduleAsynchronous");
    scheduled_ = true;
    hdStartScheduler();
    throwOnHdError("hdStartScheduler");
    scheduler_started_ = true;
  } catch (...) {
    shutDown();
    throw;
  }
}

OpenHapticsDevice::~OpenHapticsDevice() { shutDown(); }

void OpenHapticsDevice::shutDown() {
  if (scheduler_started_) {
    force_.write(Vec3d{});  // release the hand before the servo loop ends
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    hdStopScheduler();
    scheduler_started_ = false;
  }
  if (scheduled_) {
    hdUnschedule(callback_);
    scheduled_ = false;
  }
  if (device_ != HD_INVALID_HANDLE) {
    hdDisableDevice(device_);
    device_ = HD_INVALID_HANDLE;
  }
}

HDCallbackCode HDCALLBACK OpenHapticsDevice::servo(void* data) {
  auto* self = static_cast<OpenHapticsDevice*>(data);
  hdBeginFrame(self->device_);
  HDdouble position_mm[3] = {0.0, 0.0, 0.0};
  HDdouble transform[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  HDint buttons = 0;
  hdGetDoublev(HD_CURRENT_POSITION, position_mm);
  hdGetDoublev(HD_CURRENT_TRANSFORM, transform);  // column-major 4 x 4: rotation columns 0-2, translation (mm)
  hdGetIntegerv(HD_CURRENT_BUTTONS, &buttons);
  DeviceSample& s = self->pose_.back();
  const double p_m[3] = {1e-3 * position_mm[0], 1e-3 * position_mm[1], 1e-3 * position_mm[2]};
  s.position_m = self->map_.offset_m + deviceToScene(p_m) * self->map_.scale;
  // Scene orientation = M R_device (the stylus frame expressed in the scene frame).
  double r[3][3];
  for (int col = 0; col < 3; ++col) {
    const double c[3] = {transform[4 * col + 0], transform[4 * col + 1], transform[4 * col + 2]};
    const Vec3d sc = deviceToScene(c);
    for (int row = 0; row < 3; ++row) r[row][col] = sc[row];
  }
  quaternionOf(r, s.orientation);
  s.buttons = static_cast<std::uint32_t>(buttons);
  self->pose_.publish();
  self->force_.update();
  const Vec3d f = sceneToDevice(self->force_.front());
  const HDdouble force_n[3] = {f.x, f.y, f.z};
  hdSetDoublev(HD_CURRENT_FORCE, force_n);
  hdEndFrame(self->device_);
  // A device error (e.g. the force or velocity limit tripped) is counted; the servo loop keeps running so the
  // device recovers when the user lets go. The haptic loop's safety chain already clamps and rate-limits.
  if (HD_DEVICE_ERROR(hdGetError())) self->servo_errors_.fetch_add(1, std::memory_order_relaxed);
  return HD_CALLBACK_CONTINUE;
}

DeviceSample OpenHapticsDevice::read(std::uint64_t, double t_s) {
  pose_.update();
  DeviceSample s = pose_.front();
  s.t_s = t_s;
  return s;
}

}  // namespace inc
