// chooseMeshSpacing: the default lattice spacing of a mesh body from its volume and surface area.
#include "host/scene/default_spacing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace inc {

ChosenSpacing chooseMeshSpacing(double volume_m3, double area_m2) {
  const double by_count = std::cbrt(volume_m3 / kDefaultSpheresPerBody);
  const double by_thickness = volume_m3 / area_m2;
  const double raw = std::min(by_count, by_thickness);
  ChosenSpacing c;
  // Rounded down to a tenth of a millimetre, so the value reads well in the written scene and never exceeds the rule.
  c.spacing_m = std::max(1e-4, std::floor(raw * 1e4) * 1e-4);
  char why[200];
  std::snprintf(why, sizeof why, "%s: mesh volume %.4g cm^3, area %.4g cm^2, about %.0f spheres",
                by_count <= by_thickness ? "about 1000 spheres" : "two layers across the thickness 2V/A",
                volume_m3 * 1e6, area_m2 * 1e4, volume_m3 / (c.spacing_m * c.spacing_m * c.spacing_m));
  c.why = why;
  return c;
}

}  // namespace inc
