// Greedy colouring of constraints so that no two constraints of one colour share a particle (parallel Gauss-Seidel).
#pragma once

#include <cstdint>
#include <vector>

namespace inc {

struct ConstraintColoring {
  std::vector<std::int32_t> color;          // per constraint
  std::vector<std::int32_t> color_offsets;  // size colors + 1: constraints of colour k are
  std::vector<std::int32_t> order;          // order[color_offsets[k] .. color_offsets[k+1]), ascending
  int colorCount() const { return color_offsets.empty() ? 0 : int(color_offsets.size()) - 1; }
};

// Constraint c touches particles ids[offsets[c] .. offsets[c+1]). Particles with fixed[p] != 0 (inverse
// mass 0) are never written, so sharing them does not conflict; pass an empty `fixed` to treat all as
// movable. Greedy first-fit in constraint order: deterministic, at most (max conflict degree + 1) colours.
// Throws std::invalid_argument on an index out of range.
ConstraintColoring colorConstraints(const std::vector<std::int32_t>& offsets, const std::vector<std::int32_t>& ids,
                                    std::size_t particle_count, const std::vector<std::uint8_t>& fixed = {});

// True when no two constraints of one colour share a movable particle and every constraint has a colour.
bool coloringIsValid(const ConstraintColoring& coloring, const std::vector<std::int32_t>& offsets,
                     const std::vector<std::int32_t>& ids, std::size_t particle_count,
                     const std::vector<std::uint8_t>& fixed = {});

}  // namespace inc
