// The scene's static colliders (`colliders`) in the solvers' form, and the check that the organ starts outside them.
#pragma once

#include <string>
#include <vector>

#include "host/compiled/compiled_scene.h"
#include "host/io/mesh.h"
#include "physics/pbd_collision.h"

namespace inc {

struct StaticColliders {
  std::vector<pbd::PlaneCollider<double>> planes;  // n . x >= offset is free
  std::vector<pbd::BoxCollider<double>> boxes;
};
StaticColliders staticColliders(const std::vector<ColliderSpec>& specs);

// The colliders as triangles for drawing (RenderLayers::colliders): a plane as a square of side 2 * half_size
// centred where `centre` (the organ's) projects onto it, a box as its 12 faces' triangles, outward.
TriangleMesh colliderMesh(const std::vector<ColliderSpec>& specs, const Vec3d& centre, double half_size);
// colliderMesh around `points` (the organ at rest): centred on their bounding box, planes as wide as its diagonal
// on each side.
TriangleMesh colliderMeshAround(const std::vector<ColliderSpec>& specs, const std::vector<Vec3d>& points);

// Throws InputError(scene.file, "colliders[k]", reason) when any of `points` (the organ's sphere centres or nodal
// points at rest, m) lies inside collider k: behind a plane, or strictly inside a box. The solvers would push
// those parts out in the first substep, a jump no scene means. `what` names the points in the message.
void checkCollidersClear(const CompiledScene& scene, const std::vector<Vec3d>& points, const std::string& what);

}  // namespace inc
