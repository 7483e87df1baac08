// The viewer's app object behind runViewer: its state and the steps of one frame (not public viewer API).
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <string>

#include "viewer/live_plots.h"
#include "viewer/model_layers.h"
#include "viewer/orbit_camera.h"
#include "viewer/splat_renderer.h"
#include "viewer/surface_renderer.h"
#include "viewer/viewer_app.h"
#include "viewer/zbuffer_collision_gl.h"

struct GLFWwindow;

namespace inc::viewer {

// The GL objects that draw a frame and the styles they draw with.
struct SceneRenderers {
  SurfaceRenderer surface, tool;
  SplatRenderer surface_splats, particle_splats;
  ModelLayerRenderer model_layers;
  ZBufferCollider collider;
  SurfaceStyle style;
  SurfaceStyle tool_style;
  SplatParams splat_params;
  SplatCloud particle_cloud;  // the particle layer's splats (their radius sizes the marked-point splats)
};

// This frame's framebuffer, window and camera.
struct FrameView {
  ViewCamera cam;
  int fb_w = 1, fb_h = 1;    // framebuffer pixels
  int win_w = 1, win_h = 1;  // window, screen coordinates
  double px_scale = 1.0;     // framebuffer pixels per screen coordinate
};

// This frame's cursor: the real mouse or the scripted one.
struct PointerInput {
  double x = 0, y = 0;           // screen coordinates, origin top-left
  double gl_x = 0, gl_y = 0;     // framebuffer pixels, origin bottom-left (GL's)
  bool scripted_cursor = false;  // placed by ViewerOptions::cursor_* or scripted_mouse, not the mouse
  bool scripted_down = false;    // scripted_mouse's left button
  bool inFramebuffer(const FrameView& v) const { return gl_x >= 0 && gl_y >= 0 && gl_x < v.fb_w && gl_y < v.fb_h; }
};

// The tool under the mouse: its settings, this frame's tip and contact, and the grasp / cut drag in progress.
struct ToolState {
  ToolMode mode = ToolMode::Camera;
  ToolCollision collision = ToolCollision::DepthBuffer;
  double press_depth_m = 0.0;
  double grasp_radius_m = 0.0;
  double blade_length_m = 0.0;
  bool active = false;                     // the left button is down in grasp / cut mode and an event was sent
  ToolKind active_kind = ToolKind::Grasp;  // of the press (a mode switch mid-drag still releases it)
  double view_depth = 0;                   // m, the pressed tip's view depth: the drag moves the tip in that plane
  Vec3d sent;                              // the last tip sent
  bool valid = false;                      // this frame has a tip
  Vec3d tip, surface_hit;                  // the tip, and the drawn surface under the cursor (when the tip is on it)
  bool tip_on_surface = false;             // this frame's tip is surface_hit pressed in by press_depth_m
  double haptic_shift_m = 0.0;             // pointer pose = tip + plane normal x this (frozen while a drag is held)
  ZContact contact;                        // of the active collision mode
};

// Panel state that outlives a frame.
struct UiState {
  std::map<std::size_t, double> knob_editing;  // rebuild knobs: the slider's value until released
  bool show_help = false;
  std::string status;  // the last screenshot written
};

// Screenshots (P), recorded frames (V) and the scripted run's final screenshot.
struct CaptureState {
  bool want_shot = false;  // this frame
  bool recording = false;
  int shot_counter = 0, record_counter = 0;
};

class ViewerApp {
 public:
  // Needs the window's GL context current and ImGui initialised for it; borrows all three arguments.
  ViewerApp(const ViewerOptions& opt, GLFWwindow* window, SimRunner& runner);
  ViewerApp(const ViewerApp&) = delete;
  ViewerApp& operator=(const ViewerApp&) = delete;

  // Until the window closes or a scripted run has drawn its frames.
  bool running() const;
  // One displayed frame: simulation, input, scene, tool, panels, captures, swap.
  void frame();

 private:
  // Setup (viewer_app.cpp, viewer_draw.cpp).
  void frameScene();         // the orbit camera framing the model; sets the scene radius
  void applyCameraOption();  // ViewerOptions::camera over the framing
  void uploadToolMesh();

  // The simulation (viewer_app.cpp).
  void stepSimulation();  // pump, model layers wanted, the newest snapshot
  void measureFrameRate();
  void beginFrame();  // framebuffer and window sizes, ImGui's new frame

  // Input (viewer_input.cpp).
  void readPointer();
  void handleCameraMouse();
  void handleShortcuts();

  // The tool under the mouse (viewer_tool.cpp).
  void placeToolOnSurface();
  void placeToolOffSurface(bool supported);
  void followToolDrag();
  bool toolSupported() const;
  bool toolButtonDown() const;
  void sendToolEvents(bool supported, bool down);
  void sendToolEvent(const ToolEvent& e);
  void driveHapticPointer(bool down);
  void updateTool();

  // Drawing (viewer_draw.cpp).
  void uploadSnapshot();
  void clearFrame();
  void drawScene();
  void drawOverlays();
  void drawToolTip();

  // ImGui panels (viewer_ui.cpp).
  void drawPanels();
  void drawMainPanel();
  void drawRunControls();
  void drawKnobPanels();
  void drawPlotPanels();
  void drawLayersPanel();
  void drawForceScale(const RenderLayers& rl);
  void drawToolPanel();
  void drawToolModes();
  void drawToolSizes();
  void drawToolContact();
  void drawCaptureButtons();
  void drawHelp();
  void drawStatusBar();

  // After the frame is drawn (viewer_app.cpp).
  void reportFrame();
  void captureFrame();

  const ViewerOptions& opt_;
  GLFWwindow* win_;
  SimRunner& runner_;
  const bool scripted_;  // a scripted run of opt_.frames frames

  SceneRenderers r_;
  ViewLayers layers_;
  SimSnapshot snap_;
  std::uint64_t version_ = 0;
  bool need_upload_ = true;
  bool layers_wanted_ = false;  // snapshots carry the model's RenderLayers
  OrbitCamera orbit_;
  double scene_radius_ = 0.1;  // m, half the model's bounding-box diagonal
  LivePlots plots_;
  double force_scale_m_per_n_ = 0.0;  // fixed scale; 0: automatic
  double force_scale_used_ = 0.0;
  ToolState tool_;
  UiState ui_;
  CaptureState capture_;
  int frame_index_ = 0;
  double last_x_ = 0, last_y_ = 0;  // the previous frame's cursor, for drags
  std::chrono::steady_clock::time_point t_prev_;
  FrameView view_;
  PointerInput pointer_;
};

}  // namespace inc::viewer
