// Facts about a metaball model's sphere graph.
#include "host/assembly/metaball_model.h"

#include <numeric>
#include <vector>

namespace inc {

int sphereGraphComponents(const MetaballModel& m) {
  std::vector<int> parent(m.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& l : m.links) parent[find(l[0])] = find(l[1]);
  int c = 0;
  for (std::size_t i = 0; i < m.size(); ++i) c += find(int(i)) == int(i);
  return c;
}

}  // namespace inc
