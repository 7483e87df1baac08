// Analytic answers the trade-off sweep measures against: a cantilever sagging and a bar hanging under its own weight.
#pragma once

#include <string>
#include <vector>

#include "host/scene/scene.h"
#include "physics/vec3.h"

namespace inc {

// A scene whose static answer is known in closed form (linear elasticity, small strain). Detected from the
// geometry, the single `fixed` box and gravity; tools must be absent.
struct AnalyticCase {
  enum class Kind { None, Cantilever, HangingBar };
  Kind kind = Kind::None;
  int axis = 2;        // the axis the observable is measured along (gravity's axis)
  double down = -1.0;  // sign of gravity along `axis`: displacements along it count as positive
  int end_axis = 0;    // the free end is the extreme of end_sign * X[end_axis] over the rest positions
  double end_sign = 1.0;
  double length_m = 0.0;     // free length: from the clamp box's face to the free end
  double width_m = 0.0;      // cantilever: section along y
  double height_m = 0.0;     // cantilever: section along gravity (z)
  double omega1 = 0.0;       // rad/s: first mode that the load excites (bending / axial)
  double reference_m = 0.0;  // the analytic observable (tip deflection / tip drop)
  double max_strain = 0.0;   // largest strain of the analytic solution (linear theory needs it small)
  std::string describe;      // one line for the report
};

// Cantilever: a beam or box clamped by one fixed box over its x-min end (whole section, less than half the
// length), gravity along -z. Reference: Euler-Bernoulli tip deflection q L^4 / (8 E I).
// Hanging bar: a beam or box, gravity along one axis only, clamped by one fixed box over the whole section at
// the end gravity points away from (less than half the length), free length at least twice the section. Reference: the
// tip drop of a bar in uniaxial stress under its own weight, rho g L^2 / (2 E) (hangingBarDisplacement at s = L).
AnalyticCase detectAnalyticCase(const Scene& scene);

// The Euler-Bernoulli cantilever tip deflection q L^4 / (8 E I) under own weight (q = rho g b h,
// I = b h^3 / 12), in m. L free length, b width (y), h height (along gravity).
double eulerBernoulliTipDeflection(double length, double width, double height, double youngs_modulus_pa,
                                   double density_kg_m3, double gravity);

// Axial displacement (m, along gravity) at distance s below the clamp of a bar of free length L hanging under
// its own weight, in uniaxial stress: sigma(s) = rho g (L - s), u(s) = rho g (2 L s - s^2) / (2 E).
double hangingBarDisplacement(double s, double length, double youngs_modulus_pa, double density_kg_m3, double gravity);

// The observable of an analytic case from rest and current positions: the mean displacement along
// `axis` (sign `down`) of the particles within a quarter spacing of the free end (the last layer).
// For Kind::None: the magnitude of the mean displacement (centroid motion).
double analyticObservable(const AnalyticCase& c, const std::vector<Vec3d>& rest, const std::vector<Vec3d>& now,
                          double spacing);

}  // namespace inc
