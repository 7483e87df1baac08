// Greedy first-fit constraint colouring and its validity check.
#include "model/graph_coloring.h"

#include <stdexcept>
#include <string>

namespace inc {

namespace {
void checkIndices(const std::vector<std::int32_t>& offsets, const std::vector<std::int32_t>& ids, std::size_t n) {
  if (offsets.empty()) return;
  if (offsets.front() != 0 || std::size_t(offsets.back()) != ids.size())
    throw std::invalid_argument("colorConstraints: offsets do not span the id array");
  for (std::size_t c = 0; c + 1 < offsets.size(); ++c)
    if (offsets[c + 1] < offsets[c]) throw std::invalid_argument("colorConstraints: offsets decrease");
  for (std::int32_t p : ids)
    if (p < 0 || std::size_t(p) >= n)
      throw std::invalid_argument("colorConstraints: particle index " + std::to_string(p) + " out of range");
}
bool movable(const std::vector<std::uint8_t>& fixed, std::int32_t p) { return fixed.empty() || fixed[p] == 0; }
}  // namespace

ConstraintColoring colorConstraints(const std::vector<std::int32_t>& offsets, const std::vector<std::int32_t>& ids,
                                    std::size_t particle_count, const std::vector<std::uint8_t>& fixed) {
  checkIndices(offsets, ids, particle_count);
  const std::size_t nc = offsets.empty() ? 0 : offsets.size() - 1;
  ConstraintColoring out;
  out.color.assign(nc, -1);
  std::vector<std::vector<std::int32_t>> used(particle_count);  // colours already touching each particle
  std::vector<std::int64_t> forbidden_stamp;                    // forbidden_stamp[col] == c: taken for c
  int colors = 0;
  for (std::size_t c = 0; c < nc; ++c) {
    for (std::int32_t k = offsets[c]; k < offsets[c + 1]; ++k) {
      const std::int32_t p = ids[k];
      if (!movable(fixed, p)) continue;
      for (std::int32_t col : used[p]) forbidden_stamp[col] = std::int64_t(c);
    }
    int col = 0;
    while (col < colors && forbidden_stamp[col] == std::int64_t(c)) ++col;
    if (col == colors) {
      ++colors;
      forbidden_stamp.push_back(-1);
    }
    out.color[c] = col;
    for (std::int32_t k = offsets[c]; k < offsets[c + 1]; ++k)
      if (movable(fixed, ids[k])) used[ids[k]].push_back(col);
  }
  out.color_offsets.assign(std::size_t(colors) + 1, 0);
  for (std::size_t c = 0; c < nc; ++c) ++out.color_offsets[out.color[c] + 1];
  for (int k = 0; k < colors; ++k) out.color_offsets[k + 1] += out.color_offsets[k];
  out.order.resize(nc);
  std::vector<std::int32_t> fill(out.color_offsets.begin(), out.color_offsets.end() - 1);
  for (std::size_t c = 0; c < nc; ++c) out.order[fill[out.color[c]]++] = std::int32_t(c);
  return out;
}

bool coloringIsValid(const ConstraintColoring& coloring, const std::vector<std::int32_t>& offsets,
                     const std::vector<std::int32_t>& ids, std::size_t particle_count,
                     const std::vector<std::uint8_t>& fixed) {
  const std::size_t nc = offsets.empty() ? 0 : offsets.size() - 1;
  if (coloring.color.size() != nc || coloring.order.size() != nc) return false;
  // owner[p] = last constraint of the colour being checked that touched p
  std::vector<std::int64_t> owner(particle_count, -1);
  std::vector<std::uint8_t> seen(nc, 0);
  for (int k = 0; k < coloring.colorCount(); ++k) {
    for (std::int32_t s = coloring.color_offsets[k]; s < coloring.color_offsets[k + 1]; ++s) {
      const std::int32_t c = coloring.order[s];
      if (c < 0 || std::size_t(c) >= nc || seen[c] || coloring.color[c] != k) return false;
      seen[c] = 1;
      for (std::int32_t q = offsets[c]; q < offsets[c + 1]; ++q) {
        const std::int32_t p = ids[q];
        if (!movable(fixed, p)) continue;
        if (owner[p] >= 0 && owner[p] != c && coloring.color[owner[p]] == k) return false;
        owner[p] = c;
      }
    }
  }
  for (std::size_t c = 0; c < nc; ++c)
    if (!seen[c]) return false;
  return true;
}

}  // namespace inc
