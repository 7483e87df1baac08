// Samples solid geometry (box, beam, sphere, ellipsoid, closed triangle mesh) into lattice particles.
#pragma once

#include <string>
#include <vector>

#include "host/compiled/model_specs.h"
#include "host/io/mesh.h"
#include "physics/vec3.h"

namespace inc {

// Cubic lattice of cell centres with spacing s. Each sample owns one cell of volume s^3; `jitter` in
// [0, 0.5) moves every sample by a deterministic pseudo-random offset of up to jitter * s per axis (a
// function of `seed` and the sample's lattice index only, so it does not depend on thread count).
struct LatticeSpec {
  double spacing = 0.005;  // m, > 0
  double jitter = 0.0;     // fraction of spacing
  unsigned seed = 1;
};

// Box of full extents `size` centred at `center`: n_a = max(1, round(size_a / s)) cells per axis, centred,
// so the sampled block is n_a * s long (equal to size_a when size_a is a multiple of s). Order: x fastest.
std::vector<Vec3d> sampleBox(const Vec3d& center, const Vec3d& size, const LatticeSpec& lattice);

// Lattice points (cell centres of a lattice with a node cell centred at `center`) inside the ellipsoid
// with semi-axes `radii` (a sphere when all are equal).
std::vector<Vec3d> sampleEllipsoid(const Vec3d& center, const Vec3d& radii, const LatticeSpec& lattice);

// Lattice points inside a closed, outward-oriented triangle mesh. Inside means a non-zero winding number,
// computed per lattice column by casting a ray along +z and summing the signed crossings of the faces
// above the point (faces binned by their xy bounds, so the cost is ~ columns x faces per column).
std::vector<Vec3d> sampleMesh(const TriangleMesh& mesh, const LatticeSpec& lattice);

// Winding number of a closed mesh about point p along the +z ray (1 inside an outward-oriented mesh,
// 0 outside). Ray/edge and ray/vertex coincidences are decided by a consistent half-open rule, so a
// ray through a shared edge is counted once.
int meshWindingNumber(const TriangleMesh& mesh, const Vec3d& p);

// Samples a scene geometry that is not a mesh (box, beam, sphere, ellipsoid). Throws InputError naming
// `file` and the geometry key for bad sizes or an empty result; Kind::Mesh needs sampleMesh.
std::vector<Vec3d> sampleGeometry(const GeometrySpec& g, const std::string& file);

}  // namespace inc
