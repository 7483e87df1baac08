// The per-frame substep limit: how many substeps a frame may take before it is refused, and the refusal's text.
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>

#include "base/format_number.h"
#include "model/input_error.h"

namespace inc {

// A frame's work budget, in point-substeps (one substep of one MLS point or PBD sphere): about 5-30 s of one
// loaded CPU core, well under a second on a GPU. Automatic limit = budget / points, kept within
// [kMinFrameSubstepLimit, kMaxFrameSubstepLimit]: the floor keeps a large but sensibly stiff model running, the
// ceiling bounds a small model, whose substeps cost their fixed overhead (~0.1-0.6 ms on the CPU) whatever its
// size. The shipped scenes take at most 267 substeps per frame (beam, 2048 points: limit 4882).
inline constexpr double kFrameWorkBudget = 1.0e7;
inline constexpr int kMinFrameSubstepLimit = 1000;
inline constexpr int kMaxFrameSubstepLimit = 20000;

// The substeps one frame may take: `max_substeps` (solver.max_substeps) when > 0, else the automatic limit for a
// model of `points` points or spheres.
inline int frameSubstepLimit(std::size_t points, int max_substeps) {
  if (max_substeps > 0) return max_substeps;
  const double by_work = kFrameWorkBudget / double(std::max<std::size_t>(points, 1));
  return int(std::clamp(by_work, double(kMinFrameSubstepLimit), double(kMaxFrameSubstepLimit)));
}

// The rule behind frameSubstepLimit(points, max_substeps), for messages.
inline std::string frameSubstepLimitRule(std::size_t points, int max_substeps) {
  if (max_substeps > 0) return "solver.max_substeps = " + std::to_string(max_substeps);
  return "automatic: " + formatNumber(kFrameWorkBudget) + " point-substeps / " + std::to_string(points) +
         " points, within [" + std::to_string(kMinFrameSubstepLimit) + ", " + std::to_string(kMaxFrameSubstepLimit) +
         "]; solver.max_substeps sets it";
}

// Why a frame was refused: `what` ("MLS substeps", "PBD substeps x iterations") the frame needs `needed` of, more
// than `limit`; `keys`: the scene keys that lower the need (what the model's cost follows from).
inline std::string substepLimitReason(const std::string& what, double needed, int limit, const std::string& rule,
                                      const std::string& keys) {
  return "the frame needs " + formatNumber(needed) + " " + what + ", more than the limit of " + std::to_string(limit) +
         " per frame (" + rule + "); refused instead of running for minutes per frame: change " + keys +
         ", or raise solver.max_substeps";
}

// The keys an MLS model's substep count follows from (stable step ~ spacing / sqrt(E / density), over frame_dt_s).
inline constexpr const char* kMlsSubstepKeys =
    "geometry.spacing_m (coarser), material.youngs_modulus_pa (softer), solver.frame_dt_s (shorter) or "
    "solver.safety (larger)";

// Refuses, as bad input naming `key`, a fixed count of `substeps` per frame above the limit for `points`.
inline void checkFixedSubstepsFit(int substeps, std::size_t points, int max_substeps, const std::string& file,
                                  const std::string& key = "solver.substeps") {
  const int limit = frameSubstepLimit(points, max_substeps);
  if (substeps > limit)
    throw InputError(file, key,
                     std::to_string(substeps) + " substeps per frame exceed the frame's limit of " +
                         std::to_string(limit) + " (" + frameSubstepLimitRule(points, max_substeps) + ")");
}

// The keys a PBD model's substeps follow from (automatic: gravity's sag per substep under a tenth of the spacing).
inline constexpr const char* kPbdSubstepKeys =
    "solver.substeps (fewer; 0: automatic), solver.frame_dt_s (shorter) or geometry.spacing_m (larger)";

// "" when a frame of `substeps` PBD substeps fits the limit for `spheres`, else why it is refused.
inline std::string pbdSubstepRefusal(int substeps, std::size_t spheres, int max_substeps,
                                     const std::string& keys = kPbdSubstepKeys) {
  const int limit = frameSubstepLimit(spheres, max_substeps);
  if (substeps <= limit) return "";
  return substepLimitReason("PBD substeps", double(substeps), limit, frameSubstepLimitRule(spheres, max_substeps),
                            keys);
}

}  // namespace inc
