// Input checks for the sphere packer: closedness, orientation, volume and triangle-triangle self-intersection.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "host/io/mesh.h"

namespace inc {

struct PackInputReport {
  int welded_vertices = 0;          // vertices merged with an earlier vertex at bit-identical coordinates
  int removed_triangles = 0;        // triangles with a repeated vertex index (after welding) dropped
  int zero_area_triangles = 0;      // kept; they carry no normal and so do not affect distances or signs
  bool flipped = false;             // the surface was consistently inward-oriented and has been flipped
  int self_intersecting_faces = 0;  // faces in an intersecting pair, when tolerated (see below)
  double volume = 0.0;              // enclosed volume after repair (mesh units^3)
  std::string repairs;              // one line listing the repairs made, "" when none
};

// Prepares a copy of a mesh for packing. Repairs what is safe and says so (welding bit-identical
// duplicate vertices, dropping triangles with a repeated index, flipping a consistently inward-oriented
// surface); rejects the rest with InputError(file, key, reason): empty, non-finite coordinates, bad
// indices, open (boundary edges), non-manifold edges, inconsistent orientation, zero volume,
// self-intersection. The reason names the first offending edge or triangle pair.
// Small local self-intersections (real scanned organs have a few folded triangles) are tolerated when the
// faces involved are at most `max_self_intersecting_fraction` of all faces: the packer decides inside by
// ray parity, which such folds only disturb locally; they are then listed in `repairs` as tolerated.
PackInputReport preparePackInput(TriangleMesh& mesh, const std::string& file, const std::string& key = "mesh",
                                 double max_self_intersecting_fraction = 0.0);

}  // namespace inc
