// Swept cut surfaces carried from the rest configuration to the current one (viewer layer).
#include "host/sim/dissection_render_layers.h"

#include <algorithm>

#include "host/assembly/skin_binding.h"

namespace inc {

void CutLayerBinding::bind(Bound& into, const std::vector<Vec3d>& points, const MetaballModel& m) {
  if (points.empty() || m.size() < 2) return;
  TriangleMesh cloud;  // vertices only: bindSkin needs no triangles for the weights
  cloud.vertices = points;
  const int k = std::min<int>(4, int(m.size()) - 1);  // bindSkin looks at k + 1 spheres to taper the weights
  const SkinBinding b = bindSkin(cloud, m, k, "<viewer layers>");
  for (std::size_t v = 0; v < points.size(); ++v) {
    into.rest.push_back(points[v]);
    for (int j = 0; j < 4; ++j) {
      const std::size_t slot = v * std::size_t(k) + std::size_t(std::min(j, k - 1));
      const std::int32_t s = b.sphere[slot];
      into.sphere.push_back(s);
      into.weight.push_back(j < k ? b.weight[slot] : 0.0);
    }
  }
  into.k = 4;
}

void CutLayerBinding::update(const std::vector<const SweptSurface*>& swept, const MetaballModel& spheres) {
  // A cheap fingerprint of what the binding depends on: sizes and coordinate sums.
  double key[3] = {0, double(spheres.size()), 0};
  for (const SweptSurface* s : swept)
    if (s && !s->empty()) {
      key[0] += double(s->vertices.size());
      for (const Vec3d& v : s->vertices) key[2] += v.x + 2 * v.y + 3 * v.z;
    }
  for (const Vec3d& c : spheres.rest_centers) key[2] += 13 * c.x + 17 * c.y + 19 * c.z;
  if (std::equal(key, key + 3, key_)) return;
  std::copy(key, key + 3, key_);

  rest_centres_ = spheres.rest_centers;
  swept_ = Bound{};
  swept_triangles_.clear();
  std::vector<Vec3d> verts;
  for (const SweptSurface* s : swept) {
    if (!s || s->empty()) continue;
    const int base = int(verts.size());
    verts.insert(verts.end(), s->vertices.begin(), s->vertices.end());
    for (const auto& t : s->triangles) swept_triangles_.push_back({base + t[0], base + t[1], base + t[2]});
  }
  bind(swept_, verts, spheres);
  if (swept_.rest.size() != verts.size()) swept_triangles_.clear();  // nothing to bind to
}

void CutLayerBinding::move(const Bound& b, const std::vector<Vec3d>& rest_centres, const std::vector<Vec3d>& now,
                           std::vector<Vec3d>& out) {
  out.resize(b.rest.size());
  for (std::size_t v = 0; v < b.rest.size(); ++v) {
    Vec3d d;
    for (int j = 0; j < b.k; ++j) {
      const std::size_t slot = v * std::size_t(b.k) + std::size_t(j);
      const std::size_t s = std::size_t(b.sphere[slot]);
      d += (now[s] - rest_centres[s]) * b.weight[slot];
    }
    out[v] = b.rest[v] + d;
  }
}

void CutLayerBinding::apply(const std::vector<Vec3d>& sphere_positions, RenderLayers& out) const {
  if (sphere_positions.size() != rest_centres_.size()) return;  // update() not called for these spheres
  move(swept_, rest_centres_, sphere_positions, out.swept_surface.vertices);
  out.swept_surface.triangles = swept_triangles_;
}

}  // namespace inc
