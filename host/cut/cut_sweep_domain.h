// The swept surface's parameter domain: the blade strip unfolded isometrically into the plane, 3D <-> domain maps.
#pragma once

#include <array>
#include <vector>

#include "host/cut/cut_swept_surface.h"

namespace inc {

using Vec2d = std::array<double, 2>;

// The strip of a SweptSurface (pose k: vertices 2k base, 2k+1 tip) laid flat triangle by triangle: each swept
// triangle keeps its edge lengths and its orientation (counter-clockwise in the domain = the strip's normal
// motion x blade), so the domain is the surface's own metric wherever the strip is developable (a blade swept
// along an arc) and a per-triangle isometry otherwise. Coordinates in metres. The cut walls are triangulated
// here (section 5.5 of the paper: constrained Delaunay "on the sweep surface").
struct SweepDomain {
  std::vector<Vec2d> uv;           // per swept vertex
  std::vector<int> boundary;       // swept vertex ids of the strip's outline, counter-clockwise
  std::vector<double> boundary_s;  // arc length at each boundary vertex (size boundary.size() + 1)
  double diameter = 0.0;           // of the domain's bounding box (m)
  Vec3d box_lo, box_hi;            // bounding box of the swept surface (m)
  double perimeter() const { return boundary_s.back(); }
};

// Throws InputError("cut", "swept surface", reason) for fewer than two poses, a vertex count that is not a set
// of poses, triangles that are not the strip pattern of sweepSurface, non-finite vertices, a zero-area strip or
// an outline that folds over itself once unfolded (a blade path turning back over its own sweep).
SweepDomain unfoldSweptSurface(const SweptSurface& surface);

// A point's place relative to the swept surface: the closest swept triangle (lowest index on ties), the closest
// point on it, its unit normal, the signed offset from its plane (the side: >= 0 is +), and the domain position
// of the point's projection onto that triangle's plane (barycentric coordinates extended beyond the triangle,
// so points beyond the strip's edge map beyond the outline).
struct SweepProjection {
  int triangle = -1;
  Vec3d closest, normal;
  double distance = 0.0, offset = 0.0;
  Vec2d uv{0.0, 0.0};
};
// The closest triangle comes from `query` (built on `surface`: the brute-force scan's triangle and point, far runs
// of triangles skipped).
SweepProjection projectOntoSweep(const SweptSurface& surface, const SweepDomain& domain, const SweptSurfaceQuery& query,
                                 const Vec3d& p);

// The 3D point of domain position uv: the unfolded triangle containing it (or, outside the strip, the nearest
// one with extended barycentric coordinates) mapped back affinely.
Vec3d liftFromDomain(const SweptSurface& surface, const SweepDomain& domain, const Vec2d& uv);

// Position along the outline (arc length from boundary vertex 0, counter-clockwise) of the outline point nearest
// to uv, and the outline point at arc length s (taken modulo the perimeter) with its outward unit normal.
double outlinePosition(const SweepDomain& domain, const Vec2d& uv);
Vec2d outlinePoint(const SweepDomain& domain, double s, Vec2d* outward = nullptr);
// True when uv lies inside the unfolded outline (even-odd rule).
bool insideOutline(const SweepDomain& domain, const Vec2d& uv);

}  // namespace inc
