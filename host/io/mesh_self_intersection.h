// Triangle-triangle self-intersection of a surface mesh, and the load-time rule that refuses it.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "host/io/mesh.h"

namespace inc {

// Pairs of triangles (a < b) that intersect other than along their shared vertices or edge: triangles with
// no common vertex that cross or overlap, triangles sharing one vertex whose opposite edge pierces the
// other, and coplanar neighbours across an edge that fold onto each other. Touching at a single point is
// not reported. Found with a BVH over triangle boxes; at most `max_pairs` are returned.
std::vector<std::array<int, 2>> findSelfIntersections(const TriangleMesh& mesh, std::size_t max_pairs = 16);

// Share of faces that may be involved in self-intersections before a mesh is refused. Real scanned organs have a
// few folded triangles; every model decides inside by ray parity (majority of three rays) or by the nearest
// surface point, which such folds only disturb locally. More than this is a shape error no model can fill.
constexpr double kToleratedSelfIntersectingFraction = 0.01;

// Refuses (InputError naming `file` and `key`) a mesh whose self-intersecting faces exceed `tolerated_fraction`
// of all faces; the message names the first intersecting pair. Returns the number of tolerated faces.
int requireFewSelfIntersections(const TriangleMesh& mesh, const std::string& file, const std::string& key,
                                double tolerated_fraction = kToleratedSelfIntersectingFraction);

}  // namespace inc
