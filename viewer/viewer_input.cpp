// The viewer's mouse and keyboard: the cursor (real or scripted), camera drags and zoom, keyboard shortcuts.
#include <algorithm>
#include <cmath>

#include "viewer/gl_api.h"

#include <GLFW/glfw3.h>
#include <imgui.h>

#include "viewer/viewer_app_internal.h"

namespace inc::viewer {

namespace {

// The keys that toggle a layer (the Layers panel shows the same keys).
struct LayerKey {
  int key;
  bool ViewLayers::*layer;
};
constexpr LayerKey kLayerKeys[] = {
    {GLFW_KEY_1, &ViewLayers::surface},     {GLFW_KEY_2, &ViewLayers::splats},
    {GLFW_KEY_3, &ViewLayers::particles},   {GLFW_KEY_4, &ViewLayers::wireframe},
    {GLFW_KEY_5, &ViewLayers::spheres},     {GLFW_KEY_6, &ViewLayers::nodal_points},
    {GLFW_KEY_7, &ViewLayers::constrained}, {GLFW_KEY_8, &ViewLayers::swept_surface},
    {GLFW_KEY_9, &ViewLayers::forces},      {GLFW_KEY_0, &ViewLayers::colliders},
    {GLFW_KEY_T, &ViewLayers::tool},
};

// G / C switch to that tool, or back to the camera when it is already on.
ToolMode toggledMode(ToolMode current, ToolMode key_mode) { return current == key_mode ? ToolMode::Camera : key_mode; }

}  // namespace

void ViewerApp::readPointer() {
  PointerInput& p = pointer_;
  glfwGetCursorPos(win_, &p.x, &p.y);
  p.scripted_cursor = opt_.cursor_x >= 0.0 && opt_.cursor_y >= 0.0;
  if (p.scripted_cursor) {
    p.x = opt_.cursor_x * view_.win_w;
    p.y = opt_.cursor_y * view_.win_h;
  }
  p.scripted_down = false;
  if (opt_.scripted_mouse) {
    double sx = -1, sy = -1;
    p.scripted_down = opt_.scripted_mouse(frame_index_, sx, sy);
    if (sx >= 0.0 && sy >= 0.0) {
      p.scripted_cursor = true;
      p.x = sx * view_.win_w;
      p.y = sy * view_.win_h;
    }
  }
  p.gl_x = p.x * view_.px_scale;
  p.gl_y = view_.fb_h - p.y * view_.px_scale;
}

void ViewerApp::handleCameraMouse() {
  const ImGuiIO& io = ImGui::GetIO();
  if (!io.WantCaptureMouse) {
    const double dx = pointer_.x - last_x_, dy = pointer_.y - last_y_;
    const bool shift = glfwGetKey(win_, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS;
    const bool alt = glfwGetKey(win_, GLFW_KEY_LEFT_ALT) == GLFW_PRESS;
    const bool left = glfwGetMouseButton(win_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
    // In grasp / cut mode the left button belongs to the tool; alt + left or the middle button orbit.
    const bool left_orbits = tool_.mode == ToolMode::Camera || alt;
    if ((left && !shift && left_orbits && !tool_.active) ||
        glfwGetMouseButton(win_, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS)
      orbit_.orbit(dx, dy);
    if (glfwGetMouseButton(win_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS || (left && shift))
      orbit_.pan(dx * view_.px_scale, dy * view_.px_scale, view_.fb_h);
    if (io.MouseWheel != 0.0f) {
      if (glfwGetKey(win_, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS)
        tool_.press_depth_m = std::max(0.0, tool_.press_depth_m + 0.02 * scene_radius_ * io.MouseWheel);
      else
        orbit_.zoom(std::pow(0.9, double(io.MouseWheel)));
    }
  }
  last_x_ = pointer_.x;
  last_y_ = pointer_.y;
}

void ViewerApp::handleShortcuts() {
  if (ImGui::GetIO().WantCaptureKeyboard) return;
  if (ImGui::IsKeyPressed(GLFW_KEY_SPACE)) runner_.setPaused(!runner_.paused());
  if (ImGui::IsKeyPressed(GLFW_KEY_N)) runner_.stepOnce();
  if (ImGui::IsKeyPressed(GLFW_KEY_R)) runner_.reset();
  if (ImGui::IsKeyPressed(GLFW_KEY_F)) frameScene();
  if (ImGui::IsKeyPressed(GLFW_KEY_P)) capture_.want_shot = true;
  if (ImGui::IsKeyPressed(GLFW_KEY_V)) capture_.recording = !capture_.recording;
  if (ImGui::IsKeyPressed(GLFW_KEY_H) || ImGui::IsKeyPressed(GLFW_KEY_F1)) ui_.show_help = !ui_.show_help;
  for (const LayerKey& k : kLayerKeys)
    if (ImGui::IsKeyPressed(k.key)) layers_.*k.layer = !(layers_.*k.layer);
  if (ImGui::IsKeyPressed(GLFW_KEY_G)) tool_.mode = toggledMode(tool_.mode, ToolMode::Grasp);
  if (ImGui::IsKeyPressed(GLFW_KEY_C)) tool_.mode = toggledMode(tool_.mode, ToolMode::Cut);
  if (ImGui::IsKeyPressed(GLFW_KEY_MINUS)) runner_.setTimeScale(runner_.timeScale() * 0.5);
  if (ImGui::IsKeyPressed(GLFW_KEY_EQUAL)) runner_.setTimeScale(runner_.timeScale() * 2.0);
  if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE)) glfwSetWindowShouldClose(win_, GLFW_TRUE);
}

}  // namespace inc::viewer
