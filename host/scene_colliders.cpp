// The scene's static colliders in the solvers' form, and the start-outside check.
#include "host/scene_colliders.h"

#include "host/input_error.h"

namespace inc {

StaticColliders staticColliders(const std::vector<ColliderSpec>& specs) {
  StaticColliders out;
  for (const ColliderSpec& c : specs) {
    if (c.kind == "plane")
      out.planes.push_back({c.normal, dot(c.normal, c.point)});
    else
      out.boxes.push_back({c.min, c.max});
  }
  return out;
}

void checkCollidersClear(const Scene& scene, const std::vector<Vec3d>& points, const std::string& what) {
  for (std::size_t k = 0; k < scene.colliders.size(); ++k) {
    const ColliderSpec& c = scene.colliders[k];
    std::size_t inside = 0;
    for (const Vec3d& x : points) {
      if (c.kind == "plane") {
        inside += dot(c.normal, x - c.point) < 0.0;
      } else {
        bool in = true;
        for (int a = 0; a < 3; ++a) in = in && x[a] > c.min[a] && x[a] < c.max[a];
        inside += in;
      }
    }
    if (inside > 0)
      throw InputError(scene.file, "colliders[" + std::to_string(k) + "]",
                       std::to_string(inside) + " of the organ's " + std::to_string(points.size()) + " " + what +
                           " start inside this " + c.kind + " (the organ must start outside its colliders)");
  }
}

}  // namespace inc
