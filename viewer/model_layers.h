// The viewer's model layers from SimulationModel::renderLayers: metaball spheres, MLS nodal points, fixed and held
// particles, the swept cut surface and force arrows, each with its own colour and toggle.
#pragma once

#include <array>

#include "host/sim/simulation_model.h"
#include "viewer/overlay_renderer.h"
#include "viewer/sphere_renderer.h"
#include "viewer/splat_renderer.h"

namespace inc::viewer {

struct ModelLayerToggles {
  bool spheres = false;       // metaball spheres, ray-cast at their radius
  bool nodal_points = false;  // MLS nodal points as view-facing splats
  bool constrained = false;   // fixed particles and particles held by a tool (with spheres: those spheres recoloured)
  bool swept_surface = true;  // the scalpel's swept surface, translucent
  bool forces = true;         // force arrows, drawn on top
  bool colliders = true;      // the scene's static colliders (planes, boxes), translucent grey
};

// Layer colours (linear RGB; splats and spheres get the headlight on top of these).
struct ModelLayerColours {
  static constexpr std::array<float, 3> sphere{0.85f, 0.72f, 0.50f};
  static constexpr std::array<float, 3> nodal{0.30f, 0.85f, 0.40f};
  static constexpr std::array<float, 3> fixed{1.00f, 0.85f, 0.10f};
  static constexpr std::array<float, 3> held{0.85f, 0.30f, 0.90f};
  static constexpr std::array<float, 4> swept{0.25f, 0.75f, 1.00f, 0.45f};
  static constexpr std::array<float, 4> collider{0.55f, 0.57f, 0.60f, 0.35f};
  static constexpr std::array<float, 4> tool_force{1.00f, 0.50f, 0.00f, 1.0f};
  static constexpr std::array<float, 4> particle_force{0.95f, 0.95f, 0.95f, 1.0f};
};

// Forces below this are not scaled up to full length by the automatic scale, so the round-off of a resting grasp
// (float32 positions resolve ~4e-9 m at 5 cm: ~4e-3 N per sphere at compliance 1e-6 m/N) stays short.
constexpr double kForceScaleFloorN = 1e-2;

// Metres of arrow per newton: `fixed_m_per_n` when > 0, else the longest arrow is a quarter of scene_radius_m
// (forces under kForceScaleFloorN drawn shorter). 0 when there is no force to draw.
double forceArrowScale(const std::vector<ForceArrow>& forces, double fixed_m_per_n, double scene_radius_m);

// Splat radius of a marked point set: 0.6 x its median nearest-neighbour spacing (medianNearestSpacing),
// at most point_radius_m when that is > 0 (sparse sets: the particle layer's radius).
double markerRadius(const std::vector<Vec3d>& points, double point_radius_m);

class ModelLayerRenderer {
 public:
  ModelLayerRenderer();  // needs a current GL context

  // Fixed, held and nodal points are splats of markerRadius(points, point_radius_m) (the viewer passes 1.15 x
  // the particle layer's radius, so a sparse marked set covers the plain particle splats).
  void upload(const RenderLayers& layers, double point_radius_m);
  // The opaque layers (spheres, fixed / held particles, nodal points): depth-tested, writing depth. Draw before
  // the particle layer so that a marked particle shows over its plain splat.
  void drawOpaque(const ViewCamera& cam, const ModelLayerToggles& on, const SplatParams& splat);
  // The translucent colliders and swept surface, after everything opaque (no depth write).
  void drawTranslucent(const ViewCamera& cam, const ModelLayerToggles& on);
  // Force arrows on top of everything, `m_per_n` metres per newton; width 3 px (tool) and 2 px (particle).
  void drawForces(const ViewCamera& cam, const ModelLayerToggles& on, double m_per_n);
  const RenderLayers& layers() const { return layers_; }

 private:
  RenderLayers layers_;
  SphereRenderer spheres_;
  SplatRenderer nodal_, fixed_, held_;
  OverlayRenderer overlay_;
};

}  // namespace inc::viewer
