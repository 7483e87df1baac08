// Uploads a model's RenderLayers and draws them: impostor spheres, point splats, translucent and on-top overlays.
#include "viewer/model_layers.h"

#include <algorithm>
#include <cmath>

#include "viewer/splat_sources.h"

namespace inc::viewer {

double forceArrowScale(const std::vector<ForceArrow>& forces, double fixed_m_per_n, double scene_radius_m) {
  if (fixed_m_per_n > 0) return fixed_m_per_n;
  double fmax = 0;
  for (const ForceArrow& a : forces)
    if (isFinite(a.force_n)) fmax = std::max(fmax, norm(a.force_n));
  return fmax > 0 ? 0.25 * scene_radius_m / std::max(fmax, kForceScaleFloorN) : 0.0;
}

double markerRadius(const std::vector<Vec3d>& points, double point_radius_m) {
  const double own = 0.6 * medianNearestSpacing(points);
  if (own > 0 && point_radius_m > 0) return std::min(own, point_radius_m);
  return own > 0 ? own : point_radius_m;  // both 0: particleSplats' own rule
}

ModelLayerRenderer::ModelLayerRenderer() = default;

void ModelLayerRenderer::upload(const RenderLayers& layers, double point_radius_m) {
  layers_ = layers;
  // Sphere i is particle i (RenderLayers): fixed and held spheres are marked for the constrained layer.
  std::vector<std::uint8_t> marks(layers.sphere_centres.size(), 0);
  for (std::int32_t i : layers.fixed_ids)
    if (i >= 0 && std::size_t(i) < marks.size()) marks[std::size_t(i)] = 1;
  for (std::int32_t i : layers.held_ids)
    if (i >= 0 && std::size_t(i) < marks.size()) marks[std::size_t(i)] = 2;
  spheres_.upload(layers.sphere_centres, layers.sphere_radii, marks);
  nodal_.upload(
      particleSplats(layers.nodal_points, markerRadius(layers.nodal_points, point_radius_m), ModelLayerColours::nodal));
  fixed_.upload(
      particleSplats(layers.fixed_points, markerRadius(layers.fixed_points, point_radius_m), ModelLayerColours::fixed));
  held_.upload(
      particleSplats(layers.held_points, markerRadius(layers.held_points, point_radius_m), ModelLayerColours::held));
}

void ModelLayerRenderer::drawOpaque(const ViewCamera& cam, const ModelLayerToggles& on, const SplatParams& splat) {
  if (on.spheres)
    spheres_.draw(cam, {ModelLayerColours::sphere, ModelLayerColours::fixed, ModelLayerColours::held}, on.constrained);
  if (on.constrained) {
    fixed_.draw(cam, splat);
    held_.draw(cam, splat);
  }
  if (on.nodal_points) nodal_.draw(cam, splat);
}

void ModelLayerRenderer::drawTranslucent(const ViewCamera& cam, const ModelLayerToggles& on) {
  if (on.colliders && !layers_.colliders.triangles.empty()) {
    OverlayStyle s;
    s.rgba = ModelLayerColours::collider;
    overlay_.draw(cam, layers_.colliders, s);
  }
  if (!on.swept_surface || layers_.swept_surface.triangles.empty()) return;
  OverlayStyle s;
  s.rgba = ModelLayerColours::swept;
  overlay_.draw(cam, layers_.swept_surface, s);
}

void ModelLayerRenderer::drawForces(const ViewCamera& cam, const ModelLayerToggles& on, double m_per_n) {
  if (!on.forces || layers_.forces.empty() || !(m_per_n > 0)) return;
  std::vector<Vec3d> particle, tool;
  for (const ForceArrow& a : layers_.forces) {
    if (!isFinite(a.force_n) || !isFinite(a.origin)) continue;
    const bool is_tool = a.kind == ForceArrowKind::Tool;
    const double width = (is_tool ? 3.0 : 2.0) * pixelSizeAt(cam, a.origin);
    arrowTriangles(cam, a.origin, a.origin + a.force_n * m_per_n, width, is_tool ? tool : particle);
  }
  OverlayStyle s;
  s.depth_test = false;
  s.rgba = ModelLayerColours::particle_force;
  overlay_.draw(cam, particle, s);
  s.rgba = ModelLayerColours::tool_force;  // the tool's reaction over the particles' arrows
  overlay_.draw(cam, tool, s);
}

}  // namespace inc::viewer
