// Brute-force fixed-radius neighbour lists (test oracle), parallel over queries.
#include "cpu_fallback/neighbor_bruteforce.h"

#include <stdexcept>

#include "base/parallel.h"
#include "physics/distance.h"

namespace inc::cpu {

template <typename T>
NeighborLists bruteForceNeighbors(const std::vector<Vec3<T>>& queries, const std::vector<Vec3<T>>& points,
                                  const std::vector<T>& radii, bool self) {
  if (radii.empty()) throw std::invalid_argument("bruteForceNeighbors: no radius given");
  const bool per_query = radii.size() == queries.size() && radii.size() > 1;
  const std::int64_t nq = std::int64_t(queries.size());
  std::vector<std::vector<std::int32_t>> lists(queries.size());
  parallelFor(nq, [&](std::int64_t q) {
    const T r = per_query ? radii[q] : radii[0];
    const T r2 = r * r;
    for (std::size_t j = 0; j < points.size(); ++j) {
      if (self && std::int64_t(j) == q) continue;
      if (distance2Exact(queries[q], points[j]) <= r2) lists[q].push_back(std::int32_t(j));
    }
  });
  NeighborLists out;
  out.offsets.resize(queries.size() + 1, 0);
  for (std::size_t q = 0; q < queries.size(); ++q) out.offsets[q + 1] = out.offsets[q] + std::int64_t(lists[q].size());
  out.indices.reserve(std::size_t(out.offsets.back()));
  for (auto& l : lists) out.indices.insert(out.indices.end(), l.begin(), l.end());
  return out;
}

template NeighborLists bruteForceNeighbors<float>(const std::vector<Vec3f>&, const std::vector<Vec3f>&,
                                                  const std::vector<float>&, bool);
template NeighborLists bruteForceNeighbors<double>(const std::vector<Vec3d>&, const std::vector<Vec3d>&,
                                                   const std::vector<double>&, bool);

}  // namespace inc::cpu
