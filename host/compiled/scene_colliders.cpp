// The scene's static colliders in the solvers' form, and the start-outside check.
#include "host/compiled/scene_colliders.h"

#include <algorithm>
#include <cmath>

#include "model/input_error.h"

namespace inc {

StaticColliders staticColliders(const std::vector<ColliderSpec>& specs) {
  StaticColliders out;
  for (const ColliderSpec& c : specs) {
    if (c.kind == "plane")
      out.planes.push_back({c.normal, dot(c.normal, c.point), c.friction});
    else
      out.boxes.push_back({c.min, c.max, c.friction});
  }
  return out;
}

TriangleMesh colliderMesh(const std::vector<ColliderSpec>& specs, const Vec3d& centre, double half_size) {
  TriangleMesh m;
  const auto quad = [&](const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {  // counter-clockwise
    const int k = int(m.vertices.size());
    m.vertices.insert(m.vertices.end(), {a, b, c, d});
    m.triangles.push_back({k, k + 1, k + 2});
    m.triangles.push_back({k, k + 2, k + 3});
  };
  for (const ColliderSpec& c : specs) {
    if (c.kind == "plane") {
      const Vec3d n = c.normal;
      const Vec3d o = centre - n * dot(n, centre - c.point);
      // Any two unit vectors spanning the plane, (u, v, n) right-handed.
      const Vec3d seed = std::fabs(n.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
      Vec3d u = cross(seed, n);
      u = u * (half_size / norm(u));
      const Vec3d v = cross(n, u);
      quad(o - u - v, o + u - v, o + u + v, o - u + v);
    } else {
      const Vec3d& a = c.min;
      const Vec3d& b = c.max;
      quad({a.x, a.y, a.z}, {a.x, b.y, a.z}, {b.x, b.y, a.z}, {b.x, a.y, a.z});  // z = min, facing -z
      quad({a.x, a.y, b.z}, {b.x, a.y, b.z}, {b.x, b.y, b.z}, {a.x, b.y, b.z});  // z = max
      quad({a.x, a.y, a.z}, {b.x, a.y, a.z}, {b.x, a.y, b.z}, {a.x, a.y, b.z});  // y = min
      quad({a.x, b.y, a.z}, {a.x, b.y, b.z}, {b.x, b.y, b.z}, {b.x, b.y, a.z});  // y = max
      quad({a.x, a.y, a.z}, {a.x, a.y, b.z}, {a.x, b.y, b.z}, {a.x, b.y, a.z});  // x = min
      quad({b.x, a.y, a.z}, {b.x, b.y, a.z}, {b.x, b.y, b.z}, {b.x, a.y, b.z});  // x = max
    }
  }
  return m;
}

TriangleMesh colliderMeshAround(const std::vector<ColliderSpec>& specs, const std::vector<Vec3d>& points) {
  if (specs.empty() || points.empty()) return colliderMesh(specs, Vec3d(), 0.1);
  Vec3d lo = points.front(), hi = points.front();
  for (const Vec3d& p : points)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  return colliderMesh(specs, (lo + hi) * 0.5, std::max(norm(hi - lo), 1e-3));
}

void checkCollidersClear(const CompiledScene& scene, const std::vector<Vec3d>& points, const std::string& what) {
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
