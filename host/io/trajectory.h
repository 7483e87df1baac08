// Device samples (pose and buttons at a time) and trajectory files of them: reading, writing, checking.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "physics/vec3.h"

namespace inc {

// One reading of a device: tool-tip position in the scene frame (metres), orientation as a unit
// quaternion (w, x, y, z), button bit mask.
struct DeviceSample {
  double t_s = 0.0;
  Vec3d position_m;
  double orientation[4] = {1.0, 0.0, 0.0, 0.0};
  std::uint32_t buttons = 0;
};

// A trajectory: samples in increasing time. Text file, one sample a line:
//   t_s x_m y_m z_m qw qx qy qz buttons
// '#' starts a comment. Numbers are written as C99 hex floats by writeTrajectory so that a recorded
// session is replayed bit-exactly; decimal input is accepted for hand-authored files.
struct Trajectory {
  std::vector<DeviceSample> samples;
};
Trajectory loadTrajectory(const std::string& path);  // throws InputError(path, "line N", reason)
void writeTrajectory(const std::string& path, const Trajectory& trajectory);
// Checks times strictly increase, finite values, unit quaternions (|q| within 1e-3 of 1).
void validateTrajectory(const Trajectory& trajectory, const std::string& file);

}  // namespace inc
