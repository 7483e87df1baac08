// Compact CSR neighbour lists, the common currency of every fixed-radius query (host copy).
#pragma once

#include <cstdint>
#include <vector>

namespace inc {

// Query q's neighbours are indices[offsets[q] .. offsets[q+1]), ascending by point index.
// A point j is a neighbour of q when |x_q - x_j|^2 <= r^2 (closed ball, computed without FMA in the
// input precision on both backends). Self-queries leave out q itself.
struct NeighborLists {
  std::vector<std::int64_t> offsets;  // size queries + 1; int64 so that 1.6e7 x 30+ never overflows
  std::vector<std::int32_t> indices;
  std::size_t queryCount() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  std::size_t count(std::size_t q) const { return std::size_t(offsets[q + 1] - offsets[q]); }
};

}  // namespace inc
