// The closed surface mesh of a scene's body: the primitive tessellated near geometry.spacing, or the mesh file.
#include "host/assembly/scene_surface.h"

#include <algorithm>
#include <cmath>

#include "host/assembly/organ_shapes.h"
#include "model/input_error.h"

namespace inc {

TriangleMesh sceneSurfaceMesh(const CompiledScene& scene) {
  const GeometrySpec& g = scene.geometry;
  const double h = g.spacing > 0 ? g.spacing : 0.005;
  switch (g.kind) {
    case GeometrySpec::Kind::Box:
    case GeometrySpec::Kind::Beam: {
      const double longest = std::max({g.size.x, g.size.y, g.size.z});
      const int div = std::clamp(int(std::ceil(longest / h)), 2, 64);
      return makeBoxMesh(g.size * 0.5, div, g.center);
    }
    case GeometrySpec::Kind::Sphere:
      return makeSphereMesh(g.radius, std::clamp(int(std::ceil(g.radius / h)) * 2, 4, 40), g.center);
    case GeometrySpec::Kind::Ellipsoid: {
      const double rmax = std::max({g.radii.x, g.radii.y, g.radii.z});
      TriangleMesh m = makeSphereMesh(1.0, std::clamp(int(std::ceil(rmax / h)) * 2, 4, 40));
      for (auto& v : m.vertices) v = g.center + Vec3d(v.x * g.radii.x, v.y * g.radii.y, v.z * g.radii.z);
      return m;
    }
    case GeometrySpec::Kind::Mesh: {
      TriangleMesh m = loadMesh(g.mesh_path);
      for (auto& v : m.vertices) v *= g.mesh_scale;
      requireClosedMesh(m, scene.file, "geometry.mesh");
      return m;
    }
  }
  throw InputError(scene.file, "geometry.kind", "unknown geometry");
}

}  // namespace inc
