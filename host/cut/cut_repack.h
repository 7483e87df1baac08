// Algorithm 1 (section 5.4): nodal points of a finished cut -> new spheres (boundary / medial / middle points,
// eq. 14 down-sampling, radius to the nearest boundary point, merging small spheres), and their links.
#pragma once

#include <cstdint>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/cut/cut_swept_surface.h"
#include "model/neighbor_lists.h"

namespace inc {

// The points to re-pack, in the rest configuration, and context points: points of the spheres that stay around
// them (sampled alike), which take part in the boundary test and the boundary distance but are not packed, so
// that the face a group shares with the spheres that stay is not mistaken for the tissue's surface.
struct RepackPoints {
  std::vector<Vec3d> rest;            // m
  std::vector<double> mass;           // kg, > 0 (ignored for context points)
  std::vector<std::uint8_t> context;  // 1: a context point; empty: none
  NeighborLists visible;              // symmetric supports (all points) with every pair across a cut removed
  double spacing = 0.0;               // m, the sampling lattice spacing
  double support = 0.0;               // m, radius of `visible`
  std::size_t size() const { return rest.size(); }
};

struct RepackSettings {
  double boundary_offset = 0.3;  // (0, 1): |mean_j (X_j - X_i)| > offset * support marks i as boundary
  double spacing_factor = 0.5;   // eq. 14: d = factor * max over a group's medial points of their distance to the cut
  double sphere_budget = 1.0;    // > 0: a group keeps at most ceil(budget * group mass / reference_mass) spheres
  double reference_mass = 0.0;   // kg, > 0: the mass of a typical sphere of the organ
  double max_radius = 0.0;       // m; > 0: no new sphere is larger, d is at most 2/3 of it (0: no cap). Without a
                                 // cap the medial balls of successive cuts grow towards the organ's thickness
  std::vector<const SweptSurface*> earlier_cuts;  // also block an isolated point's view of a sphere centre
};

enum RepackPointClass : std::uint8_t { kRepackMiddle = 0, kRepackBoundary = 1, kRepackMedial = 2 };

struct RepackResult {
  std::vector<Vec3d> centres;             // m
  std::vector<double> radii;              // m
  std::vector<double> masses;             // kg, the sum of the masses of the points each took
  std::vector<std::int32_t> owner;        // per point: the new sphere that took its mass (its Voronoi cell's)
  std::vector<std::uint8_t> point_class;  // per point: RepackPointClass
  int groups = 0;                         // connected components of the supports
  std::size_t boundary = 0, medial = 0, middle = 0;
  std::size_t packed = 0;                       // spheres Algorithm 1 placed at eq. 14's spacing
  std::size_t merged = 0;                       // of those, merged away (small first) to respect the budget
  double spacing_min = 0.0, spacing_max = 0.0;  // eq. 14's d over the groups (m)
  double merge_spacing_max = 0.0;               // the largest spacing the merging widened d to (m)
};

// Per group (component of `points.visible` among the points that are not context):
//  1. boundary points: fewer than 4 visible neighbours, or a one-sided support (the centroid of the visible
//     neighbours, context included, off by more than boundary_offset * support): the organ's surface and, since
//     supports never cross a cut, the cut walls;
//  2. d_b(i) = distance to the nearest boundary point (context included); medial points: non-boundary points
//     whose d_b is within spacing / 4 of the largest d_b among their visible neighbours in the group (the ridge
//     of the distance field within the group); the others are middle points (all points are medial in a group
//     without interior points);
//  3. eq. 14: d = spacing_factor * max_medial distanceToSweptSurface(cut, X_i), at least one point spacing and
//     at most max_radius / 1.5;
//  4. Algorithm 1: medial points by decreasing d_b take a sphere when every accepted centre is farther than d;
//     then (our completion) middle points by the same rule, where the medial balls leave the group uncovered;
//  5. merging small spheres: while the group holds more than its budget, d grows by 10 % and step 4 is redone
//     (the shallow, small candidates drop out first; the survivors stay evenly spread);
//  6. every point's mass goes to its nearest centre (Voronoi cell); radius = max(d_b + spacing / 2, spacing) (the
//     distance to the nearest boundary point, which sits half a spacing inside the surface it samples), grown to
//     the cell's farthest point (the balls cover their points), all at most max_radius: uncapped, a ball that
//     reaches out of the tissue puts points and mass outside it when it is cut again (measured: 20 successive
//     cuts then drift by decimetres).
// Isolated points (components under 4 points) join the nearest sphere they see (no cut between), or become a
// debris sphere of their own.
// Deterministic. Throws InputError("repack", key, reason) on inconsistent input.
RepackResult packNodalPoints(const RepackPoints& points, const SweptSurface& cut, const RepackSettings& settings);

// Appends the spheres of `r` to `spheres` and links every new sphere to each sphere (new or old) it overlaps
// whose centre segment crosses none of `cuts` (new spheres connect only to spheres on their own side). Returns
// the number of links added.
std::size_t appendRepackedSpheres(MetaballModel& spheres, const RepackResult& r,
                                  const std::vector<const SweptSurface*>& cuts);

}  // namespace inc
