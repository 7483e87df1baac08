// Cut-surface reconstruction: the organ's surface mesh split by a planar swept surface, both cut walls capped.
#pragma once

#include <string>

#include "host/cut/cut_swept_surface.h"
#include "host/io/mesh.h"

namespace inc {

struct CutMeshResult {
  TriangleMesh positive;   // the part on the +normal side, closed: its cut wall faces -normal
  TriangleMesh negative;   // the part on the -normal side, closed: its cut wall faces +normal
  int contour_loops = 0;   // closed cut contours (one per piece of the cross-section)
  int wall_triangles = 0;  // triangles of both cut walls together
  int forced_ears = 0;     // ear-clipping steps that found no valid ear (0 on well-shaped sections)
};

// Least-squares plane of the swept surface (point = centroid, normal = mean triangle normal). Returns false when
// the surface is empty or deviates from its plane by more than `tolerance_m` (a curved cut: see docs/cutting.md).
bool planeOfSweptSurface(const SweptSurface& surface, Vec3d& point, Vec3d& normal, double tolerance_m);

// True when every point where the mesh's edges cross the plane (point, normal) lies within tol_m of the swept
// surface: the blade went through the whole cross-section, so splitting the surface by the plane is the cut.
bool sweptSurfaceSpansSection(const TriangleMesh& mesh, const SweptSurface& surface, const Vec3d& point,
                              const Vec3d& normal, double tol_m);

// Splits a closed, consistently oriented mesh by the plane (point, normal): triangles crossing the plane are
// split at the edge intersections (shared per edge, so both walls reuse the same contour vertices) and each
// closed contour is triangulated in the plane by ear clipping, oriented outward for its piece. When a vertex lies
// within 1e-7 of the mesh size of the plane, the plane is shifted along the normal by that much until it clears
// every vertex (so no sliver triangles; the cut moves by well under a micrometre on an organ).
CutMeshResult splitMeshByPlane(const TriangleMesh& mesh, const Vec3d& point, const Vec3d& normal);

// Concatenation (vertex indices of b shifted), for drawing both pieces as one surface.
TriangleMesh mergeMeshes(const TriangleMesh& a, const TriangleMesh& b);

}  // namespace inc
