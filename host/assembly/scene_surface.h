// The closed surface of a scene's body (what the skin draws, what the packer fills).
#pragma once

#include "host/compiled/compiled_scene.h"
#include "host/io/mesh.h"

namespace inc {

// Box/beam: a subdivided box; sphere/ellipsoid: a UV sphere scaled to the radii, tessellated near
// geometry.spacing; mesh: the file scaled by mesh_scale, required closed. Throws InputError(scene.file, key, reason).
TriangleMesh sceneSurfaceMesh(const CompiledScene& scene);

}  // namespace inc
