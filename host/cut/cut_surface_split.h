// Cut-surface reconstruction along any swept surface (section 5.5): crossed triangles split, CDT cut walls, slits.
#pragma once

#include <cstdint>
#include <vector>

#include <string>

#include "host/cut/cut_swept_surface.h"
#include "host/io/mesh.h"
#include "model/input_error.h"

namespace inc {

// The split stayed inconsistent after every perturbed attempt (a degenerate configuration such as a blade that
// stops exactly on a wall of an earlier cut): InputError("cut", "swept surface", reason) of its own type, so that a
// running simulation can keep the surface unsplit for that cut instead of stopping.
class CutSplitFailed : public InputError {
 public:
  explicit CutSplitFailed(const std::string& reason) : InputError("cut", "swept surface", reason) {}
};

struct SurfaceSplitOptions {
  // A crossing is kept at least this fraction of its edge away from either end vertex (and a cut-front point
  // this fraction away from its triangle's edges): a blade grazing a vertex or running along an edge moves the
  // cut curve by at most this fraction of an edge instead of leaving slivers (docs/cutting.md).
  double snap_fraction = 0.15;
  // Spacing of the points down-sampled on the swept surface inside the organ, in units of the mean length of
  // the crossed mesh edges (the wall gets the resolution of the surface around it).
  double wall_spacing_factor = 1.0;
  int smoothing_iterations = 4;
  // Attempts with the swept surface shifted by 2e-6, 1e-4 then 1e-3 of the mesh size when the crossing curve comes
  // out inconsistent (a blade exactly through a vertex of the strip's outline, a crossing curve grazing the front).
  int max_attempts = 4;
  // The mesh is a split's own output, which passed the same checks on the way out (CutSurfaceState::checked): the
  // input check (closed, manifold, oriented, no degenerate triangle; a sixth of a split) is not repeated.
  bool input_checked = false;
};

// The split surface. Input vertices keep their indices; new vertices follow: for each crossing of a mesh edge
// one copy per side, the cut-front points (one vertex shared by both walls: the slit's tip line), and the
// interior wall points (one copy per side). So each side separates along the cut, and a partial cut leaves one
// closed mesh whose two walls meet along the cut front.
struct SurfaceSplit {
  TriangleMesh mesh;
  std::vector<std::int8_t> vertex_side;       // +1 / -1: side of the swept surface (its normal: motion x blade);
                                              // 0: on the cut front, shared by both walls
  std::vector<Vec3d> binding_probe;           // per vertex: where a skin binding looks from (a new vertex: just
                                              // off the swept surface on its side; the front: just ahead of it)
  std::vector<std::int32_t> source_triangle;  // per triangle: the input triangle it is part of, -1 for a wall
  std::vector<std::uint8_t> wall;             // per triangle: 1 = cut wall (both sides)
  bool split = false;                         // false: the blade crosses no triangle (the mesh is returned unchanged)
  std::string failure;  // applySurfaceCut only: why the surface was left unsplit (CutSplitFailed), else empty
  int crossings = 0, front_points = 0, pierce_points = 0, contour_loops = 0, wall_triangles = 0, components = 0;
  int attempts = 0, chord_splits = 0;
  double wall_spacing_m = 0.0;
  double min_wall_angle_deg = 0.0, min_wall_area_m2 = 0.0;    // over the wall triangles
  double min_split_angle_deg = 0.0, min_split_area_m2 = 0.0;  // over the pieces of the crossed triangles
};

// Splits a closed, manifold, consistently oriented triangle mesh along the swept surface. Every triangle the
// surface crosses is split along the crossing curve; the region of the swept surface inside the organ is
// down-sampled and triangulated in the strip's parameter domain by constrained Delaunay with the crossing curve
// (and, for a partial cut, the cut front) as constraints; that triangulation is stitched to both sides with
// opposite orientations. Every output is closed, manifold (edges and vertices), consistently oriented and free
// of degenerate triangles, or the call throws. Throws InputError("cut", "surface mesh", reason) for an open,
// non-manifold or inconsistently oriented mesh and InputError("cut", "swept surface", reason) for a degenerate
// swept surface (see unfoldSweptSurface), and CutSplitFailed for a split that stays inconsistent after every
// attempt.
SurfaceSplit splitSurfaceBySweep(const TriangleMesh& mesh, const SweptSurface& sweep,
                                 const SurfaceSplitOptions& options = {});

// Smallest interior angle of a triangle (degrees) and its area (m^2).
double triangleMinAngleDeg(const Vec3d& a, const Vec3d& b, const Vec3d& c);
double triangleArea(const Vec3d& a, const Vec3d& b, const Vec3d& c);

// Number of vertices whose incident triangles do not form one closed fan (0 for a manifold closed mesh).
int nonManifoldVertexCount(const TriangleMesh& mesh);

}  // namespace inc
