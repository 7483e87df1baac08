// Orders a mesh's edge records by their lower vertex in linear time: the order one global sort would give.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace inc {

// Sorts `items` (each with an int `lo` in [0, vertices)) by `lo`, then each vertex's few items by `less`: a counting
// sort on `lo` and small per-vertex sorts instead of one O(E log E) sort (a cut's split and its output check order
// every edge of the surface).
template <typename Item, typename Less>
void sortByLowerVertex(std::vector<Item>& items, std::size_t vertices, Less less) {
  std::vector<std::size_t> start(vertices + 1, 0);
  for (const Item& e : items) ++start[std::size_t(e.lo) + 1];
  for (std::size_t v = 0; v < vertices; ++v) start[v + 1] += start[v];
  std::vector<Item> sorted(items.size());
  std::vector<std::size_t> fill(start.begin(), start.end() - 1);
  for (const Item& e : items) sorted[fill[std::size_t(e.lo)]++] = e;
  for (std::size_t v = 0; v < vertices; ++v) std::sort(sorted.begin() + start[v], sorted.begin() + start[v + 1], less);
  items.swap(sorted);
}

}  // namespace inc
