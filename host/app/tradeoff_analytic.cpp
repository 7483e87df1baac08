// Closed-form references of the trade-off sweep: Euler-Bernoulli cantilever, bar hanging under its own weight.
#include "host/app/tradeoff_analytic.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace inc {
namespace {

double comp(const Vec3d& v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

std::string mm(double m) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g mm", m * 1e3);
  return b;
}

}  // namespace

double eulerBernoulliTipDeflection(double length, double width, double height, double youngs_modulus_pa,
                                   double density_kg_m3, double gravity) {
  const double q = density_kg_m3 * gravity * width * height;  // N/m
  const double I = width * height * height * height / 12.0;   // m^4
  return q * std::pow(length, 4) / (8.0 * youngs_modulus_pa * I);
}

double hangingBarDisplacement(double s, double length, double youngs_modulus_pa, double density_kg_m3, double gravity) {
  // d/ds (E du/ds) = -rho g, u(0) = 0, E du/ds (L) = 0 (free end).
  return density_kg_m3 * gravity * (2.0 * length * s - s * s) / (2.0 * youngs_modulus_pa);
}

AnalyticCase detectAnalyticCase(const Scene& s) {
  AnalyticCase c;
  const GeometrySpec& g = s.geometry;
  if (g.kind != GeometrySpec::Kind::Beam && g.kind != GeometrySpec::Kind::Box) return c;
  if (s.fixed.size() != 1 || !s.tools.empty()) return c;
  const Vec3d lo{g.center.x - 0.5 * g.size.x, g.center.y - 0.5 * g.size.y, g.center.z - 0.5 * g.size.z};
  const Vec3d hi{g.center.x + 0.5 * g.size.x, g.center.y + 0.5 * g.size.y, g.center.z + 0.5 * g.size.z};
  const FixedRegion& f = s.fixed[0];
  const Vec3d gr = s.solver.gravity;
  int gaxis = -1, nonzero = 0;
  for (int k = 0; k < 3; ++k)
    if (std::abs(comp(gr, k)) > 1e-12) {
      gaxis = k;
      ++nonzero;
    }
  if (nonzero != 1) return c;
  const double gmag = std::abs(comp(gr, gaxis));
  const double E = s.material.youngs_modulus_pa, rho = s.material.density_kg_m3;
  // The fixed box covers the whole section across `axis` and one end of it (less than half the length).
  auto coversSection = [&](int axis) {
    for (int k = 0; k < 3; ++k)
      if (k != axis && (comp(f.min, k) > comp(lo, k) || comp(f.max, k) < comp(hi, k))) return false;
    return true;
  };
  auto clampsMinEnd = [&](int k) {
    return comp(f.min, k) <= comp(lo, k) && comp(f.max, k) > comp(lo, k) &&
           comp(f.max, k) < comp(lo, k) + 0.5 * comp(g.size, k);
  };
  auto clampsMaxEnd = [&](int k) {
    return comp(f.max, k) >= comp(hi, k) && comp(f.min, k) < comp(hi, k) &&
           comp(f.min, k) > comp(hi, k) - 0.5 * comp(g.size, k);
  };
  if (gaxis == 2 && comp(gr, 2) < 0.0 && coversSection(0) && clampsMinEnd(0)) {
    c.kind = AnalyticCase::Kind::Cantilever;
    c.axis = 2;
    c.down = -1.0;
    c.end_axis = 0;
    c.end_sign = 1.0;
    c.length_m = hi.x - f.max.x;
    c.width_m = g.size.y;
    c.height_m = g.size.z;
    // omega_1 = 1.8751^2 sqrt(E I / (rho A)) / L^2, I / A = h^2 / 12 (first root of 1 + cos k cosh k = 0).
    c.omega1 = 1.8751 * 1.8751 * std::sqrt(E * c.height_m * c.height_m / (12.0 * rho)) / (c.length_m * c.length_m);
    c.reference_m = eulerBernoulliTipDeflection(c.length_m, c.width_m, c.height_m, E, rho, gmag);
    // Largest bending strain at the clamp: M h / (2 E I), M = q L^2 / 2.
    c.max_strain = 3.0 * rho * gmag * c.length_m * c.length_m / (2.0 * E * c.height_m);
    c.describe = "Euler-Bernoulli tip deflection of the cantilever (L = " + mm(c.length_m) + ", b = " + mm(c.width_m) +
                 ", h = " + mm(c.height_m) + "): " + mm(c.reference_m);
    return c;
  }
  const double down = comp(gr, gaxis) < 0.0 ? -1.0 : 1.0;
  // The clamp holds the end gravity points away from: the top.
  const bool top_clamped = down < 0.0 ? clampsMaxEnd(gaxis) : clampsMinEnd(gaxis);
  if (!coversSection(gaxis) || !top_clamped) return c;
  // A bar, not a block: with nu > 0 the clamp's lateral restraint reaches about one section width into the
  // body, and uniaxial stress describes only a body much longer than that.
  const double section = std::max(comp(g.size, (gaxis + 1) % 3), comp(g.size, (gaxis + 2) % 3));
  const double free_length = down < 0.0 ? comp(f.min, gaxis) - comp(lo, gaxis) : comp(hi, gaxis) - comp(f.max, gaxis);
  if (free_length < 2.0 * section) return c;
  c.kind = AnalyticCase::Kind::HangingBar;
  c.axis = gaxis;
  c.down = down;
  c.end_axis = gaxis;
  c.end_sign = down;
  c.length_m = free_length;
  // First axial mode of a fixed-free bar: omega_1 = (pi / 2) sqrt(E / rho) / L.
  c.omega1 = 0.5 * M_PI * std::sqrt(E / rho) / c.length_m;
  c.reference_m = hangingBarDisplacement(c.length_m, c.length_m, E, rho, gmag);
  c.max_strain = rho * gmag * c.length_m / E;  // at the clamp
  c.describe =
      "tip drop of the bar hanging under its own weight, uniaxial stress rho g L^2 / (2 E) (L = " + mm(c.length_m) +
      "): " + mm(c.reference_m);
  return c;
}

double analyticObservable(const AnalyticCase& c, const std::vector<Vec3d>& rest, const std::vector<Vec3d>& now,
                          double spacing) {
  const std::size_t n = std::min(rest.size(), now.size());
  if (n == 0) return 0.0;
  if (c.kind == AnalyticCase::Kind::None) {
    Vec3d d{0, 0, 0};
    for (std::size_t i = 0; i < n; ++i) d = d + (now[i] - rest[i]);
    return std::sqrt(norm2(d)) / double(n);
  }
  double end = -1e300;
  for (std::size_t i = 0; i < n; ++i) end = std::max(end, c.end_sign * comp(rest[i], c.end_axis));
  double sum = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (c.end_sign * comp(rest[i], c.end_axis) >= end - 0.25 * spacing) {
      sum += c.down * (comp(now[i], c.axis) - comp(rest[i], c.axis));
      ++count;
    }
  return sum / count;
}

}  // namespace inc
