// The organ of a scene's BEM global model: its closed surface mesh (loaded, checked, scaled) and its supports.
#pragma once

#include <string>
#include <vector>

#include "host/compiled/model_specs.h"
#include "host/io/mesh.h"

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

}  // namespace inc
