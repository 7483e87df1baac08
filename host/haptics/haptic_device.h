// Haptic device interface (pose and buttons in, force out) and the scripted device.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "host/io/trajectory.h"
#include "physics/vec3.h"

namespace inc {

// A force-feedback device. read() and writeForce() are called only from the haptic thread, once per
// tick, in that order; implementations must not block (a real driver copies its latest state).
class HapticDevice {
 public:
  virtual ~HapticDevice() = default;
  // tick: index of the haptic tick (0, 1, ...); t_s: loop time of the tick (seconds since start).
  virtual DeviceSample read(std::uint64_t tick, double t_s) = 0;
  // Force on the user's hand in newtons, scene frame, already clamped and rate limited by the loop.
  virtual void writeForce(const Vec3d& force_n) = 0;
  // Largest force the hardware may render (newtons); the loop clamps to it.
  virtual double maxForce_n() const = 0;
  virtual std::string name() const = 0;
};

// Plays a trajectory. Mode kByTime linearly interpolates position (and normalised-lerps orientation)
// at the tick's time, holding the end points outside the range: for authored paths. Mode kByTick
// returns sample[tick] exactly (holding the last one): for bit-exact replay of a recorded session,
// independent of the real clock's jitter.
class ScriptedDevice : public HapticDevice {
 public:
  enum class Mode { kByTime, kByTick };
  ScriptedDevice(Trajectory trajectory, Mode mode, double max_force_n = 3.3);
  DeviceSample read(std::uint64_t tick, double t_s) override;
  void writeForce(const Vec3d& force_n) override {
    last_force_n_ = force_n;
    ++forces_written_;
  }
  double maxForce_n() const override { return max_force_n_; }
  std::string name() const override { return "scripted"; }
  const Vec3d& lastForce_n() const { return last_force_n_; }
  std::uint64_t forcesWritten() const { return forces_written_; }
  double duration_s() const;

 private:
  Trajectory trajectory_;
  Mode mode_;
  double max_force_n_;
  Vec3d last_force_n_;
  std::uint64_t forces_written_ = 0;
};

}  // namespace inc
