// Cut-wall triangulation: constrained Delaunay (CGAL) of the cut region in the swept surface's domain.
#pragma once

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "host/cut/cut_sweep_domain.h"

namespace inc {

// An internal consistency failure of a cut (crossing loops that do not close, constraints that intersect): the
// caller retries with a perturbed swept surface (docs/cutting.md); it is not a user error by itself.
class CutInconsistent : public std::runtime_error {
 public:
  explicit CutInconsistent(const std::string& what) : std::runtime_error(what) {}
};

struct WallDomainInput {
  std::vector<Vec2d> uv;                // per boundary node (domain coordinates, m); no two equal
  std::vector<std::uint8_t> shared;     // per node: 1 = one vertex for both walls (the cut front), 0 = one per wall
  std::vector<std::vector<int>> loops;  // closed node sequences, the region to triangulate on their left
  double spacing_m = 0.0;               // target edge length of the interior points
  int smoothing_iterations = 4;         // area-weighted centroid moves of the interior points
};

struct WallTriangulation {
  std::vector<Vec2d> interior_uv;             // points added inside the region: node ids uv.size() + i
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise in the domain
  int chord_splits = 0;                       // points added so that no inner edge joins two shared nodes
};

// Down-samples the region on a triangular lattice of the given spacing (points closer than 0.5 spacing to the
// boundary dropped), smooths them, and triangulates with the loops as constraints (CGAL
// Constrained_Delaunay_triangulation_2, exact predicates). An inner edge whose two ends are shared nodes would
// make the two walls share an edge (non-manifold), so it gets a midpoint. Throws CutInconsistent when the loops
// intersect, pass through other nodes, or do not bound a consistent region; throws InputError("cut", "build",
// ...) when the project was built without CGAL.
WallTriangulation triangulateCutWall(const WallDomainInput& input);

}  // namespace inc
