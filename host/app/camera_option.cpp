// Parsing of the viewer's --camera option (yaw, pitch, distance), with errors that name the option.
#include "host/app/camera_option.h"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "model/input_error.h"

namespace inc {

CameraAngles parseCameraAngles(const std::string& text, const std::string& option) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || end == item.c_str() || *end != '\0')
      throw InputError("", option, "\"" + item + "\" is not a number (expected YAW,PITCH[,DISTANCE])");
    if (!std::isfinite(x)) throw InputError("", option, "\"" + item + "\" is not finite");
    v.push_back(x);
  }
  if (!text.empty() && text.back() == ',') throw InputError("", option, "ends with a comma");
  if (v.size() < 2 || v.size() > 3)
    throw InputError(
        "", option,
        "expected YAW,PITCH[,DISTANCE] (degrees, degrees, metres), got " + std::to_string(v.size()) + " numbers");
  CameraAngles a;
  a.yaw_deg = v[0];
  a.pitch_deg = v[1];
  if (!(a.pitch_deg >= -89.0 && a.pitch_deg <= 89.0))
    throw InputError("", option, "the pitch must lie in [-89, 89] degrees (got " + std::to_string(a.pitch_deg) + ")");
  if (v.size() == 3) {
    a.distance_m = v[2];
    if (!(a.distance_m >= 0.0)) throw InputError("", option, "the distance must be >= 0 m (0: framed)");
  }
  return a;
}

}  // namespace inc
