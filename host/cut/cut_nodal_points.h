// Sphere -> MLS nodal points at a cut, and re-packing the nodal points into spheres once the blade leaves.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/cut/cut_swept_surface.h"
#include "model/neighbor_lists.h"

namespace inc {

struct NodalPoints {
  std::vector<Vec3d> positions;             // m
  std::vector<double> masses;               // kg, m_sphere / n for each of the sphere's n points (section 5.1)
  std::vector<std::int32_t> source_sphere;  // index of the converted sphere in the pre-cut model
  std::vector<std::int8_t> side;            // +1 / -1 side of the swept surface
  double spacing = 0.0;                     // m, the lattice spacing used
  double max_source_radius = 0.0;           // m, the largest converted sphere's radius
  std::size_t size() const { return positions.size(); }
};

struct CutOptions {
  int samples_per_diameter = 4;  // lattice cells across a sphere's diameter (the paper's uniform sampling)
  // Cuts made before this one: a sphere's points are kept only where the segment from its centre crosses none
  // of them (a sphere re-packed on one side of an earlier cut holds no material of the other side).
  std::vector<const SweptSurface*> earlier_cuts;
  // The tissue (e.g. inside the organ's rest surface): a sphere's points are kept only inside it, so that the
  // part of a ball that reaches out of the organ carries no mass (empty: everywhere).
  std::function<bool(const Vec3d&)> inside;
};

// Uniform sampling inside one sphere (section 5.1): cell centres of an n^3 lattice (cell 2 r / n) over its
// bounding cube with |x - c| < r, visible from the centre through `cuts` (segment c-x crosses none of them) and
// inside the tissue when `inside` is given; the centre alone when the lattice leaves nothing. Throws
// InputError("cut", "samples_per_diameter") unless n is in [1, 64].
std::vector<Vec3d> sampleSphere(const Vec3d& centre, double radius, int n,
                                const std::vector<const SweptSurface*>& cuts = {},
                                const std::function<bool(const Vec3d&)>& inside = {});

// Symmetric supports of radius h (closed ball, grid search) over `positions` with the visibility criterion of
// section 5.2 applied for every cut: a pair is dropped when its segment crosses one of `cuts` (decided once per
// unordered pair, lower index first, so the lists stay symmetric). `removed` (when given) gets the number of
// directed entries dropped.
NeighborLists visibleSupports(const std::vector<Vec3d>& positions, double support_radius,
                              const std::vector<const SweptSurface*>& cuts, std::size_t* removed = nullptr);
// A stroke's supports kept up to date as points and strips are added, equal to this: host/cut/cut_stroke_supports.h.

// The spheres the swept surface enters are removed and replaced by nodal points on a lattice of cell size
// 2 r / samples_per_diameter inside each sphere (cell centres with |x - c| < r; the centre alone when the lattice
// misses). Each point carries m_i / n, so the total mass is unchanged. Links touching a removed sphere and links
// crossing the swept surface are dropped; the surviving spheres are renumbered in their old order.
struct SphereCutResult {
  MetaballModel spheres;           // the model without the cut spheres
  std::vector<std::int32_t> kept;  // new sphere index -> old index
  std::vector<std::int32_t> cut;   // old indices of the converted spheres
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
  double boundary_offset = 0.3;  // (0, 1): a point whose support centroid is off by more than this * h is boundary
  double spacing_factor = 0.5;   // eq. 14: d = spacing_factor * max distance of a group's medial points to the cut
  double sphere_budget = 1.0;    // > 0: new spheres per reference mass, per group (merging, bounded count)
  double reference_mass = 0.0;   // kg, > 0; 0: the mean mass of the converted spheres. Give the organ's original
                                 // mean over successive cuts (a mean of re-packed spheres would drift)
  double max_radius = 0.0;       // m, > 0: the cap of new radii and of eq. 14's d; 0: 1.5 x the largest converted
                                 // radius (give 1.5 x the organ's original over successive cuts)
  double support_factor = 2.0;   // h = support_factor * point spacing for the supports of the classification
};

// Re-packs the nodal points into spheres by Algorithm 1 (host/cut/cut_repack.h, packNodalPoints): the points are
// grouped by the components of their visibility-filtered supports (radius support_factor * points.spacing; pairs
// crossing `surface` or an earlier cut dropped), each group's boundary / medial / middle points classified, the
// medial points down-sampled with the spacing of eq. 14, radius = distance to the nearest boundary point, small
// spheres merged down to the group's budget. Every point's mass goes to the new sphere of its Voronoi cell (exact
// mass). New spheres are appended to `spheres`; links join overlapping spheres (new-new,
// new-old) whose centre segment crosses neither `surface` nor an earlier cut (new spheres connect only to their
// own side). The budget's reference mass is options.reference_mass, or the mean mass of the converted spheres.
// Returns the number of spheres added.
std::size_t repackSpheres(MetaballModel& spheres, const NodalPoints& points, const SweptSurface& surface,
                          const RepackOptions& options = {}, const std::vector<SweptSurface>& earlier_cuts = {});

double totalMass(const MetaballModel& model);
double totalMass(const NodalPoints& points);

}  // namespace inc
