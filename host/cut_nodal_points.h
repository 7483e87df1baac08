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
  double min_radius_factor = 2.0;  // r_min = factor * nodal spacing (2 with 4 samples per diameter: r_min = r)
  double max_radius = 0.0;         // m; <= 0: the largest radius among the converted spheres
};

// Re-packs the nodal points into spheres side by side (a documented local greedy cover, docs/cutting.md): points
// are visited by decreasing clearance d to the swept surface (ties by index); an uncovered point p seeds a
// sphere: radius min(d, r_max) centred at p when d >= r_min, else radius r_min centred at k + r_min * u (k the
// closest point of the cut, u the unit direction from k to p, or the side's normal when p lies on the cut), so
// the sphere touches the cut without crossing it (Algorithm 1's radius = distance to the boundary, bounded
// below so the count stays bounded). The seed and every uncovered point of the same side inside the sphere are
// assigned to it, and the sphere's mass is the sum of its points' masses (exact mass conservation). The new
// spheres are appended to `spheres`; links are added between overlapping spheres (new-new and new-old) whose
// centre segment does not cross the swept surface. Returns the number of spheres added.
std::size_t repackSpheres(MetaballModel& spheres, const NodalPoints& points, const SweptSurface& surface,
                          double converted_max_radius, const RepackOptions& options = {});

double totalMass(const MetaballModel& model);
double totalMass(const NodalPoints& points);

}  // namespace inc
