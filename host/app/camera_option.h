// The viewer's initial camera as given on the command line (`incision view --camera YAW,PITCH[,DISTANCE]`).
#pragma once

#include <string>

namespace inc {

struct CameraAngles {
  double yaw_deg = 0;     // about the up axis; 0 looks along +y (z up) or -z (y up)
  double pitch_deg = 0;   // above the horizontal, in [-89, 89]
  double distance_m = 0;  // from the framed target; 0: the framing's own distance
};

// Parses "YAW,PITCH" or "YAW,PITCH,DISTANCE"; InputError naming `option` and the reason for anything else
// (a missing or extra number, a non-finite value, a pitch outside [-89, 89] degrees, a negative distance).
CameraAngles parseCameraAngles(const std::string& text, const std::string& option = "--camera");

}  // namespace inc
