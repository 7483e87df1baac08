// The lattice spacing chosen for a mesh body whose scene leaves geometry.spacing_m out: the rule and its explanation.
#pragma once

#include <string>

namespace inc {

// About this many spheres fill a body at the chosen spacing: enough to resolve an organ's shape and a cut through
// it, few enough that the PBD solver converges in its default iterations and a frame stays interactive on the CPU
// fallback (about 30 ms per frame for 1000 spheres on two cores; far less on a GPU).
constexpr double kDefaultSpheresPerBody = 1000.0;

struct ChosenSpacing {
  double spacing_m = 0.0;
  std::string why;  // one line for the user: which bound chose it and the body's figures
};

// spacing = min(cbrt(V / kDefaultSpheresPerBody), V / A), rounded down to 0.1 mm (at least 0.1 mm). The first term
// gives about kDefaultSpheresPerBody spheres; the second keeps at least two lattice layers across the body's
// typical thickness (V / A is half the thickness of a slab, half the radius of a rod, a third of a ball's radius),
// so a thin organ or a sheet is not sampled by one straggling layer. volume_m3 and area_m2 must be > 0.
ChosenSpacing chooseMeshSpacing(double volume_m3, double area_m2);

}  // namespace inc
