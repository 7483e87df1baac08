// Procedural closed organ-like surface meshes (sphere, box, torus, liver-like) the project ships itself.
#pragma once

#include <string>

#include "host/io/mesh.h"

namespace inc {

// Geodesic sphere: every face of an icosahedron split into frequency^2 triangles, projected onto the
// sphere. 10 f^2 + 2 vertices, 20 f^2 triangles, outward (counter-clockwise) orientation.
TriangleMesh makeSphereMesh(double radius_m, int frequency, Vec3d center = {});

// Axis-aligned box surface with `divisions` segments along each edge (shared vertices, watertight).
TriangleMesh makeBoxMesh(const Vec3d& half_extents_m, int divisions, Vec3d center = {});

// Torus around the z axis: major radius R (centre of the tube), minor radius r < R.
TriangleMesh makeTorusMesh(double major_radius_m, double minor_radius_m, int major_segments, int minor_segments,
                           Vec3d center = {});

struct LiverLikeOptions {
  int target_vertices = 8000;  // geodesic frequency is chosen so that 10 f^2 + 2 is nearest to this
  double width_m = 0.20;       // extent along x (left-right); an adult liver is about 0.2 m wide
  int variant = 0;             // 0: the reference shape; other values jitter the lobe bumps (seeded)
};

// A liver-like closed surface: a large right lobe, a smaller wedge-shaped left lobe, a notch between
// them, a flattened, concave underside. Built as a star-shaped radial field r(d) > 0 on a geodesic
// sphere followed by maps that are injective with positive Jacobian (positive scaling, a positive
// taper of y along x, a shear of y by a function of x and z), so the result is embedded and outward
// oriented by construction; the tests still check it with analyzeMesh-independent code.
TriangleMesh makeLiverLikeMesh(const LiverLikeOptions& options = {});

// Builds a shape by name for tools and scenes: "sphere", "box", "torus", "liver". Sizes are the
// defaults above scaled so that the largest extent is `size_m`; `resolution` is the approximate
// vertex count. Throws InputError(file, key, ...) for an unknown name or a non-positive size.
TriangleMesh makeOrganShape(const std::string& name, double size_m, int resolution, const std::string& file = "",
                            const std::string& key = "shape");

}  // namespace inc
