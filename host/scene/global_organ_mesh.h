// The organ of a scene's BEM global model: its surface mesh (loaded, checked, scaled), supports and scene keys.
#pragma once

#include <string>
#include <vector>

#include "host/io/mesh.h"
#include "host/scene/scene.h"
#include "host/scene/scene_json.h"

namespace inc {

// The dense BEM matrices are (3E)^2 doubles each (E triangles): 162 MB at this size, and the precompute (inverse
// and contact table) takes minutes on a CPU. A larger mesh is a render mesh by mistake.
inline constexpr int kMaxBemElements = 1500;

// The boundary condition of one boundary element: traction-free, or held (displacement zero).
enum class BemBc : unsigned char { kTraction = 0, kDisplacement = 1 };

// Loads the mesh at `path` (OBJ, PLY, STL), scales it by `scale` (metres per file unit) and checks it for the BEM:
// closed, manifold, consistently oriented (an inward mesh is flipped), positive volume, no degenerate triangle,
// at most kMaxBemElements triangles. Throws InputError(path, element, reason).
TriangleMesh loadGlobalOrganMesh(const std::string& path, double scale);

// The base boundary conditions: an element whose centroid lies in a fixed box (inclusive, to a rounding
// tolerance) is held (displacement zero), every other one is traction-free.
std::vector<BemBc> organSupports(const TriangleMesh& mesh, const std::vector<FixedRegion>& fixed);

// After the key table has read h.global_model and h.global_mesh_scale: refuses the global_* keys unless
// global_model is "bem"; with "bem", global_mesh (resolved against base_dir, loaded and checked) and global_cache
// (default: the scene file's name with .bemcache in its folder; a scene without a file caches next to the mesh).
// Throws InputError(file, "haptics.<key>", reason), also when no element of the organ lies in a `fixed` region
// (the BEM system would be singular).
void readGlobalModelKeys(const scene_json::ObjectReader& haptics, const std::string& base_dir,
                         const std::vector<FixedRegion>& fixed, HapticsSpec& h);

}  // namespace inc
