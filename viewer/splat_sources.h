// Turning what a model publishes (particles, surface) into splat clouds: surface splats and particle splats.
#pragma once

#include <array>
#include <vector>

#include "host/io/mesh.h"
#include "viewer/splat_raster.h"

namespace inc::viewer {

// One splat per surface vertex: area-weighted normal, radius 0.7 x the longest incident edge (an equilateral
// triangle's circumradius is 0.577 x its edge, so the three vertex discs cover it with margin).
SplatCloud surfaceSplats(const TriangleMesh& mesh, const std::array<float, 3>& colour);

// One view-facing splat per particle (no normal), radius `radius_m`; when radius_m <= 0 it is
// 0.6 x (bounding-box volume / n)^(1/3), the mean spacing of points filling the box.
SplatCloud particleSplats(const std::vector<Vec3d>& points, double radius_m, const std::array<float, 3>& colour);

// The median, over up to `samples` points spread through the list, of the distance to their nearest other point
// (m): the spacing of a point set even when it is split into distant groups. 0 for fewer than two points.
double medianNearestSpacing(const std::vector<Vec3d>& points, std::size_t samples = 64);

// Axis-aligned bounds of points; false when empty or non-finite.
bool pointBounds(const std::vector<Vec3d>& points, Vec3d& lo, Vec3d& hi);

}  // namespace inc::viewer
