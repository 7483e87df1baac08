// Sphere -> MLS nodal points at a cut, and re-packing the nodal points into spheres once the blade leaves.
#pragma once

#include <cstdint>
#include <vector>

#include "host/cut_swept_surface.h"
#include "host/metaball_model.h"
#include "host/neighbor_lists.h"

namespace inc {

struct NodalPoints {
  std::vector<Vec3d> positions;            // m
  std::vector<double> masses;              // kg, m_sphere / n for each of the sphere's n points (section 5.1)
  std::vector<std::int32_t> source_sphere; // index of the converted sphere in the pre-cut model
  std::vector<std::int8_t> side;           // +1 / -1 side of the swept surface
  double spacing = 0.0;                    // m, the lattice spacing used
  std::size_t size() const { return positions.size(); }
};

struct CutOptions {
  int samples_per_diameter = 4;   // lattice cells across a sphere's diameter (the paper's uniform sampling)
};

// The spheres the swept surface enters are removed and replaced by nodal points on a lattice of cell size
// 2 r / samples_per_diameter inside each sphere (cell centres with |x - c| < r; the centre alone when the lattice
// misses). Each point carries m_i / n, so the total mass is unchanged. Links touching a removed sphere and links
// crossing the swept surface are dropped; the surviving spheres are renumbered in their old order.
struct SphereCutResult {
  MetaballModel spheres;              // the model without the cut spheres
  std::vector<std::int32_t> kept;     // new sphere index -> old index
  std::vector<std::int32_t> cut;      // old indices of the converted spheres
  NodalPoints points;
  std::size_t links_removed = 0;
};
SphereCutResult cutSpheres(const MetaballModel& model, const SweptSurface& surface, const CutOptions& options = {});

// MLS support of the nodal points (radius h): brute-force fixed-radius lists with the visibility criterion
// applied (pairs whose segment crosses the swept surface removed). Returns the number of pairs removed in
// `removed` when non-null.
NeighborLists visibleNodalNeighbours(const NodalPoints& points, double support_radius, const SweptSurface& surface,
                                     std::size_t* removed = nullptr);

struct RepackOptions {
  double max_radius = 0.0;         // m; <= 0: the largest radius among the converted spheres
};

// Re-packs the nodal points into spheres side by side (a documented local cover, docs/cutting.md): the points of
// each side are grouped by the cells of a grid of size h = r_max / 0.75 (r_max: the largest converted radius
// unless options.max_radius > 0; 0.75 h is the lattice's sphere radius), one sphere per non-empty (side, cell)
// group: centre = the group's mass centroid, radius = max(0.5 r_max, distance to its farthest point), so every
// nodal point lies in the sphere that took its mass (exact mass conservation, complete cover) and the re-packed
// region keeps the original sphere density. With earlier cuts given, points are also grouped by their side of
// each earlier cut, and links are refused across any of them (successive cuts). New spheres are appended to `spheres`; links join overlapping spheres
// (new-new, new-old) whose centre segment does not cross the swept surface. Returns the number of spheres added.
std::size_t repackSpheres(MetaballModel& spheres, const NodalPoints& points, const SweptSurface& surface,
                          double converted_max_radius, const RepackOptions& options = {},
                          const std::vector<SweptSurface>& earlier_cuts = {});

double totalMass(const MetaballModel& model);
double totalMass(const NodalPoints& points);

}  // namespace inc
