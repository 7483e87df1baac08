// Makes a metaball model's sphere graph one connected component per mesh piece: links stragglers, drops the rest.
#pragma once

#include <string>

#include "host/assembly/metaball_model.h"
#include "host/io/mesh.h"

namespace inc {

// What connectSphereGraph found and did.
struct SphereGraphRepair {
  int mesh_pieces = 0;        // connected pieces of the surface mesh
  int components_before = 0;  // sphere-graph components as filled
  int components_after = 0;   // after the repair: one per mesh piece that holds spheres
  int stragglers = 0;         // spheres outside the largest component of their mesh piece, before the repair
  int linked = 0;             // of those, spheres joined to the rest by new links
  int links_added = 0;        // links added across the gaps
  int dropped = 0;            // spheres removed: no link to the rest runs inside the mesh within the reach
  double dropped_mass = 0.0;  // kg (when the model had masses), handed to the nearest kept sphere of the piece
  bool changed() const { return linked > 0 || dropped > 0; }
};

// Joins every sphere group that overlaps no other group of the same mesh piece to that piece's largest group:
// each of its spheres is linked to its nearest spheres of other groups (up to three each), accepting only links
// whose segment stays inside the mesh (a thin limb's lattice cells meet at a corner; an arm resting against the
// body must not be tied to it through the air) and whose gap between the balls is at most `max_gap`. A group that
// no such link can join is dropped and its mass goes to the nearest kept sphere of its piece. Links keep i < j,
// sorted; the result never holds a sphere without a link unless its piece holds that one sphere only.
// `surface` is the closed mesh the spheres fill (scene units); an empty one stands for a convex body of one piece
// (a box, a sphere, an ellipsoid), which holds every segment between two of its points.
SphereGraphRepair connectSphereGraph(MetaballModel& model, const TriangleMesh& surface, double max_gap);

// "211 spheres, 3 stragglers linked (5 links), 0 dropped, 1 component" for summaries and logs.
std::string describeSphereGraphRepair(const SphereGraphRepair& repair, std::size_t spheres);

}  // namespace inc
