// What every shipped scene (scenes/*.json) must do when run: the bounds its physics sets, one row per scene.
#pragma once

#include <limits>
#include <ostream>
#include <string>
#include <vector>

namespace inc::test {

// A frame counter of the scene's model, reduced over the run's frames, that must lie in [min, max].
struct CounterBound {
  enum class Over { Last, Max, Sum };
  const char* counter;
  Over over;
  double min, max;
};

// One shipped scene's run and the bounds it must meet (tests/support/shipped_scene_run.h checks them, on the CPU in
// tests/app/test_shipped_scenes.cpp and on CUDA in tests/gpu/test_shipped_scenes_gpu.cpp). Every row's comment says
// where its bounds come from. Each run must also end without a guard failure or retry, with every frame and the
// final positions finite, every surface vertex in a triangle and (sphere models) one connected sphere graph.
struct ShippedSceneBounds {
  const char* scene;               // scenes/<scene>.json
  long frames;                     // frames to run; 0: the scene's whole duration
  double energy_max_j;             // bound on kinetic + elastic energy over all frames (every scene starts at rest)
  double displacement_min_m;       // the scene's event must move the tissue at least this far (largest over frames)
  double displacement_max_m;       // ... and no further than this
  int pieces_min, pieces_max;      // pieces of the final surface (-1: the model has no surface) ...
  int debris_max = 0;              // ... not counting up to this many fragments of under kDebrisVertices vertices
  double largest_piece_min = 0.0;  // fraction of the surface's vertices in its largest piece
  std::vector<CounterBound> counters = {};
};

// A connected piece of the final surface with fewer vertices than this is a fragment (torn-off debris), not a piece.
inline constexpr int kDebrisVertices = 10;

// gtest names a failing parameter by its scene.
inline void PrintTo(const ShippedSceneBounds& row, std::ostream* os) { *os << row.scene; }

inline constexpr double kUnbounded = std::numeric_limits<double>::infinity();

// Gravity's share of an energy bound is m |g| d_max: the most potential energy the tissue can give up when no point
// moves further than d_max (damping only removes energy). Masses: density times the filled volume (lattice cells).
inline const std::vector<ShippedSceneBounds>& shippedSceneBounds() {
  using O = CounterBound::Over;
  // scene, frames, energy_max_j, displacement_min_m, displacement_max_m, pieces_min, pieces_max, debris_max,
  // largest_piece_min, counters
  static const std::vector<ShippedSceneBounds> rows = {
      // MLS cantilever, 8 x 2 x 2 cm, E 200 kPa, 34 g. Euler-Bernoulli tip deflection q L^4 / (8 E I) = 8.0 mm
      // (q = rho g A = 4.16 N/m, I = a^4 / 12); the first period (6.9 Hz) fits in the 0.25 s run, so the tip
      // reaches at least half of it and, a suddenly applied load overshooting at most to twice the static value,
      // at most 16 mm. Energy: m g d_max = 0.034 kg * 9.81 * 0.016 m. No particle may be isolated.
      {"beam", 0, 5.3e-3, 0.004, 0.016, -1, -1, 0, 0.0, {{"isolated_particles", O::Max, 0, 0}}},
      // MLS bar hanging from its top face, nu = 0: the exact tip drop rho g L^2 / (2 E) = 0.150 mm (docs/tradeoff.md);
      // damping 500/s against the first axial mode's 270 rad/s is near critical: it settles within the run with
      // little overshoot, so [half, twice] that. Energy: m g d_max = 0.034 kg * 9.81 * 0.3 mm.
      {"hanging_bar", 0, 1.0e-4, 0.075e-3, 0.30e-3, -1, -1, 0, 0.0, {{"isolated_particles", O::Max, 0, 0}}},
      // Liver (201 spheres, 0.87 kg) dropped onto a pad 1 cm below it (so every point falls at least 1 cm) on a table
      // 5.5 cm below its centre plane: no point can sink further than from z = 0 to the table, 5.5 cm (6 cm with its
      // slide). Energy: m g d_max = 0.87 * 9.81 * 0.06 m. Nothing cuts it: one piece.
      {"liver_drop", 0, 0.51, 0.01, 0.06, 1, 1},
      // Liver (0.80 kg) glued on its bed; the grasper moves 4.1 cm and the spheres it holds follow it (at least
      // 2 cm), the rest sag ~1 cm: at most 6 cm. Energy: gravity m g d_max = 0.47 J plus the grasper's work, about
      // 1/2 k d^2 with a rigid punch's k = 2 E a / (1 - nu^2) (a ~ 2.8 cm, the 20 spheres it holds; E 5 kPa):
      // 0.3 J, times 10 for the coarse lattice's stiffness over the continuum estimate.
      {"liver_grasp", 0, 3.5, 0.02, 0.06, 1, 1, 0, 0.0, {{"grasped", O::Max, 1, kUnbounded}}},
      // Steak (480 spheres, 0.52 kg) on a board: gravity compresses its 2 cm above the fixed layer by
      // rho g H^2 / (2 E) = 0.1 mm; the through cut leaves both halves on the board, so nothing moves more than a
      // tenth of the sphere spacing (1 mm). Energy: m g d_max. The through cut: two pieces, two sphere groups, no
      // nodal point left.
      {"steak_cut",
       0,
       5.1e-3,
       0.05e-3,
       1.0e-3,
       2,
       2,
       0,
       0.0,
       {{"cuts_applied", O::Last, 1, 1}, {"sphere_components", O::Last, 2, 2}, {"nodal_points", O::Last, 0, 0}}},
      // Liver cut along an arc; the grasper then pulls the cut-off tip 3.2 cm (at least 2 cm moved; with the ~1 cm
      // sag at most 6 cm). Energy as liver_grasp's. The through cut: two pieces.
      {"liver_cut",
       0,
       3.5,
       0.02,
       0.06,
       2,
       2,
       0,
       0.0,
       {{"cuts_applied", O::Last, 1, 1},
        {"sphere_components", O::Last, 2, 2},
        {"nodal_points", O::Last, 0, 0},
        {"grasped", O::Max, 1, kUnbounded}}},
      // Block without gravity cut by a haptic scalpel: only the blade touches it, pressing 4 mm, so nothing moves
      // further; the device's force is clamped at 3.3 N over a stroke of under 8 cm: at most 0.26 J of work. The
      // through cut: two pieces.
      {"haptic_cut_block",
       0,
       0.26,
       0.0,
       0.004,
       2,
       2,
       0,
       0.0,
       {{"cuts_applied", O::Last, 1, 1}, {"sphere_components", O::Last, 2, 2}}},
      // The same block and stroke, with a probe pressing 3 mm beside it: two devices of 3.3 N over under 8 cm each.
      {"haptic_two_hands",
       0,
       0.53,
       0.0,
       0.004,
       2,
       2,
       0,
       0.0,
       {{"cuts_applied", O::Last, 1, 1}, {"sphere_components", O::Last, 2, 2}}},
      // Leg skin (37k particles, no gravity: the leg carries it; docs/tearing.md), 66 frames = the grasper's whole
      // 4 cm lift over 1 s and 0.1 s of hold, by which the patch is out (on the CPU at frame 58). The grasped patch
      // follows the grasper (at least 3 cm moved); its torn flap reaches at most ~3 cm beyond it (7 cm). Energy: the
      // bonds within 2 cm of the grasped patch (~2300) each stretched to the yield strain 0.2:
      // 1/2 (1 / compliance) (0.2 h)^2 = 1.25 mJ each, 2.9 J. The tear stays on that region: at most ~1000 splits
      // (its ~770 particles), at least 50 (the patch tears out). Pieces: the leg, holding 95 % of the particles or
      // more, and the torn-out patch, with a few debris fragments (single triangles torn off the rim). The scalpel
      // removes particles along its line.
      {"leg_skin_tear",
       66,
       3.0,
       0.03,
       0.07,
       2,
       2,
       10,
       0.95,
       {{"splits", O::Sum, 50, 1000}, {"removed", O::Sum, 1, kUnbounded}}},
  };
  return rows;
}

}  // namespace inc::test
