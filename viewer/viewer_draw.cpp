// The viewer's drawing: snapshot uploads, the scene (surface, splats, particles, model layers), forces and the tool
// tip.
#include <algorithm>
#include <array>
#include <map>
#include <utility>
#include <vector>

#include "viewer/gl_api.h"
#include "viewer/splat_sources.h"
#include "viewer/viewer_app_internal.h"

namespace inc::viewer {

namespace {

ModelLayerToggles modelToggles(const ViewLayers& l) {
  ModelLayerToggles t;
  t.spheres = l.spheres;
  t.nodal_points = l.nodal_points;
  t.constrained = l.constrained;
  t.swept_surface = l.swept_surface;
  t.forces = l.forces;
  t.colliders = l.colliders;
  return t;
}

// A unit sphere for the tool tip: an octahedron refined three times, new vertices pushed out to the sphere.
TriangleMesh unitSphereMesh() {
  TriangleMesh m;
  const double t = 1.0;
  m.vertices = {{t, 0, 0}, {-t, 0, 0}, {0, t, 0}, {0, -t, 0}, {0, 0, t}, {0, 0, -t}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int level = 0; level < 3; ++level) {
    std::map<std::pair<int, int>, int> mid;
    std::vector<std::array<int, 3>> next;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const Vec3d p = m.vertices[a] + m.vertices[b];
      m.vertices.push_back(p * (1.0 / norm(p)));
      return mid[key] = int(m.vertices.size()) - 1;
    };
    for (const auto& f : m.triangles) {
      const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles.swap(next);
  }
  return m;
}

// Tool tip colours: dragging, pressed into the tissue, resting.
constexpr std::array<float, 3> kToolActive{0.95f, 0.8f, 0.2f};
constexpr std::array<float, 3> kToolInside{0.3f, 0.85f, 0.4f};
constexpr std::array<float, 3> kToolIdle{0.75f, 0.78f, 0.82f};

}  // namespace

void ViewerApp::uploadToolMesh() { r_.tool.upload(unitSphereMesh()); }

// A new snapshot's surface, splats and model layers go to the GPU once.
void ViewerApp::uploadSnapshot() {
  if (!need_upload_) return;
  if (snap_.has_surface) {
    r_.surface.upload(snap_.surface, snap_.cut_walls);
    r_.surface_splats.upload(surfaceSplats(snap_.surface, r_.style.front));
  }
  r_.particle_cloud = particleSplats(snap_.positions, opt_.particle_radius_m, {0.35f, 0.55f, 0.85f});
  r_.particle_splats.upload(r_.particle_cloud);
  r_.model_layers.upload(snap_.layers, r_.particle_cloud.radii.empty() ? 0.0 : 1.15 * r_.particle_cloud.radii.front());
  need_upload_ = false;
}

void ViewerApp::clearFrame() {
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, view_.fb_w, view_.fb_h);
  glDepthMask(GL_TRUE);
  glClearColor(0.11f, 0.12f, 0.14f, 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

void ViewerApp::drawScene() {
  clearFrame();
  const ViewCamera& cam = view_.cam;
  r_.style.wireframe = layers_.wireframe;
  if (snap_.has_surface && layers_.surface && !layers_.splats) r_.surface.draw(cam, r_.style);
  if (snap_.has_surface && layers_.splats) r_.surface_splats.draw(cam, r_.splat_params);
  const ModelLayerToggles toggles = modelToggles(layers_);
  // Marked particles (fixed, held, nodal) before the plain particle splats, so that they show over them.
  r_.model_layers.drawOpaque(cam, toggles, r_.splat_params);
  if (layers_.particles || !snap_.has_surface) r_.particle_splats.draw(cam, r_.splat_params);
  r_.model_layers.drawTranslucent(cam, toggles);
}

// Force arrows and the tool tip, on top of the scene.
void ViewerApp::drawOverlays() {
  force_scale_used_ = forceArrowScale(r_.model_layers.layers().forces, force_scale_m_per_n_, scene_radius_);
  r_.model_layers.drawForces(view_.cam, modelToggles(layers_), force_scale_used_);
  if (tool_.valid) drawToolTip();
}

void ViewerApp::drawToolTip() {
  const double r = 0.03 * scene_radius_;
  SurfaceStyle& style = r_.tool_style;
  style.front = tool_.active ? kToolActive : tool_.contact.inside ? kToolInside : kToolIdle;
  style.back = style.front;
  style.on_top = true;  // the tip stays visible when pressed into the tissue
  r_.tool.draw(view_.cam, style, frameMatrix({r, 0, 0}, {0, r, 0}, {0, 0, r}, tool_.tip));
  if (tool_.mode == ToolMode::Grasp && snap_.tool_support.grasp) {  // the grasp's reach, as a wire ball
    const double g = tool_.grasp_radius_m;
    SurfaceStyle reach = style;
    reach.wireframe = true;
    reach.on_top = false;
    r_.tool.draw(view_.cam, reach, frameMatrix({g, 0, 0}, {0, g, 0}, {0, 0, g}, tool_.tip));
  }
}

}  // namespace inc::viewer
