// The tool under the mouse: its tip on the drawn surface, its contact, grasp / cut events, the haptic pointer.
#include <cmath>
#include <vector>

#include "viewer/gl_api.h"

#include <GLFW/glfw3.h>
#include <imgui.h>

#include "viewer/orbit_camera.h"
#include "viewer/screenshot.h"
#include "viewer/viewer_app_internal.h"
#include "viewer/zbuffer_collision.h"

namespace inc::viewer {

namespace {

// Where the ray through GL pixel (px, py) meets the view plane at view depth `depth_m`; false when the ray
// runs along the plane.
bool pointInViewPlane(const ViewCamera& cam, double px, double py, double depth_m, Vec3d& out) {
  Vec3d o, dir;
  cam.pixelRay(px, py, o, dir);
  const double along = dot(dir, cam.forward);
  if (!(along > 1e-9)) return false;
  out = o + dir * ((depth_m - dot(o - cam.eye, cam.forward)) / along);
  return true;
}

}  // namespace

void ViewerApp::updateTool() {
  placeToolOnSurface();
  // Grasp / cut: press, drag and release become tool events for the simulation thread.
  const bool supported = toolSupported();
  const bool down = toolButtonDown();
  placeToolOffSurface(supported);
  followToolDrag();
  sendToolEvents(supported, down);
  driveHapticPointer(down);
}

// The z-buffer depth under the cursor places the tip on the drawn surface, pressed in by the press depth.
void ViewerApp::placeToolOnSurface() {
  ToolState& t = tool_;
  t.valid = false;
  t.tip_on_surface = false;
  t.contact = ZContact{};
  const ViewCamera& cam = view_.cam;
  const PointerInput& p = pointer_;
  if (!(layers_.tool && (p.scripted_cursor || !ImGui::GetIO().WantCaptureMouse) && p.inFramebuffer(view_))) return;
  const std::vector<float> d = readDepth(int(p.gl_x), int(p.gl_y), 1, 1);
  const double px = std::floor(p.gl_x) + 0.5, py = std::floor(p.gl_y) + 0.5;
  Vec3d hit;
  if (!pointFromWindowDepth(cam, px, py, d[0], hit)) return;
  Vec3d o, dir;
  cam.pixelRay(px, py, o, dir);
  t.tip = hit + dir * t.press_depth_m;
  t.surface_hit = hit;
  t.valid = t.tip_on_surface = true;
  if (t.collision == ToolCollision::SplatZBuffer) {
    const ViewCamera zc = cameraRayDepthCamera(cam.eye, t.tip, 0.01 * scene_radius_, cam.far_m, 33);
    // The paper's GPU z-buffer test needs oriented splats: the surface's (view-facing particle
    // discs have no back side, so nothing would ever count as inside).
    if (snap_.has_surface) t.contact = r_.collider.collide(zc, r_.surface_splats, t.tip);
  } else {
    t.contact.inside = t.press_depth_m > 0.0;
    t.contact.surface_point = hit;
    t.contact.penetration_m = t.press_depth_m;
  }
}

bool ViewerApp::toolSupported() const {
  switch (tool_.mode) {
    case ToolMode::Grasp: return snap_.tool_support.grasp;
    case ToolMode::Cut: return snap_.tool_support.cut;
    default: return false;
  }
}

// The left button for the tool: the scripted mouse's when there is one, else the real one without alt
// (alt + left orbits).
bool ViewerApp::toolButtonDown() const {
  if (opt_.scripted_mouse) return pointer_.scripted_down;
  const bool alt = glfwGetKey(win_, GLFW_KEY_LEFT_ALT) == GLFW_PRESS;
  return glfwGetMouseButton(win_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS && !alt;
}

// Off the organ a stroke (or a grasp) starts in the view plane through the orbit target, so a cut can
// begin outside the tissue like a real scalpel's.
void ViewerApp::placeToolOffSurface(bool supported) {
  if (!(supported && !tool_.active && !tool_.valid && pointer_.inFramebuffer(view_))) return;
  const ViewCamera& cam = view_.cam;
  if (pointInViewPlane(cam, pointer_.gl_x, pointer_.gl_y, cam.viewDepth(orbit_.target), tool_.tip)) tool_.valid = true;
}

// The dragged tip stays in the view plane of the press (under the cursor, at the pressed depth).
void ViewerApp::followToolDrag() {
  if (!(tool_.active && pointer_.gl_x >= 0 && pointer_.gl_y >= 0)) return;
  if (pointInViewPlane(view_.cam, pointer_.gl_x, pointer_.gl_y, tool_.view_depth, tool_.tip)) tool_.valid = true;
}

// In a haptics scene the haptic cutting tool cuts: the mouse stroke only moves its blade.
void ViewerApp::sendToolEvent(const ToolEvent& e) {
  if (!(opt_.haptic_pointer && e.kind == ToolKind::Cut)) runner_.queueTool(e);
}

void ViewerApp::sendToolEvents(bool supported, bool down) {
  ToolState& t = tool_;
  ToolEvent ev;
  ev.kind = t.active ? t.active_kind : t.mode == ToolMode::Cut ? ToolKind::Cut : ToolKind::Grasp;
  ev.axis = view_.cam.forward;
  ev.radius_m = t.grasp_radius_m;
  ev.blade_length_m = t.blade_length_m;
  if (supported && down && !t.active && t.valid && (pointer_.scripted_cursor || !ImGui::GetIO().WantCaptureMouse)) {
    t.active = true;
    t.active_kind = ev.kind;
    t.view_depth = view_.cam.viewDepth(t.tip);
    ev.phase = ToolPhase::Press;
    ev.tip = t.sent = t.tip;
    sendToolEvent(ev);
  } else if (t.active && (down && supported)) {
    if (norm(t.tip - t.sent) > 1e-3 * scene_radius_) {  // a drag event only once the tip has moved
      ev.phase = ToolPhase::Drag;
      ev.tip = t.sent = t.tip;
      sendToolEvent(ev);
    }
  } else if (t.active) {
    ev.phase = ToolPhase::Release;
    ev.tip = t.sent = t.tip;
    sendToolEvent(ev);
    t.active = false;
  }
}

// The haptic pointer: the tip's pose every frame, pressed into the tissue plane by the press depth.
void ViewerApp::driveHapticPointer(bool down) {
  if (!(opt_.haptic_pointer && tool_.valid)) return;
  const Vec3d& n = opt_.haptic_plane_normal;
  if (!tool_.active && tool_.tip_on_surface)
    tool_.haptic_shift_m = dot(opt_.haptic_plane_point_m - tool_.surface_hit, n);
  const double identity[4] = {1.0, 0.0, 0.0, 0.0};
  opt_.haptic_pointer->setPose(tool_.tip + n * tool_.haptic_shift_m, identity, down ? 1u : 0u);
}

}  // namespace inc::viewer
