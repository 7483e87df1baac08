// The viewer's entry and frame loop: options, window and ImGui setup, the simulation's snapshots, captures.
#include "viewer/viewer_app.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "model/input_error.h"
#include "viewer/gl_api.h"
#include "viewer/gl_window.h"

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include "viewer/screenshot.h"
#include "viewer/splat_sources.h"
#include "viewer/viewer_app_internal.h"

namespace inc::viewer {

namespace {

// Lets the runner own a model the caller keeps owning (ViewerOptions is passed by const reference).
class BorrowedModel : public SimulationModel {
 public:
  explicit BorrowedModel(SimulationModel& m) : m_(m) {}
  std::string name() const override { return m_.name(); }
  BackendKind backend() const override { return m_.backend(); }
  std::size_t particleCount() const override { return m_.particleCount(); }
  FrameReport advance(double dt) override { return m_.advance(dt); }
  void saveCheckpoint() override { m_.saveCheckpoint(); }
  void restoreCheckpoint() override { m_.restoreCheckpoint(); }
  void scaleTimeStep(double f) override { m_.scaleTimeStep(f); }
  void currentPositions(std::vector<Vec3d>& out) const override { m_.currentPositions(out); }
  bool currentSurface(TriangleMesh& out) const override { return m_.currentSurface(out); }
  MemoryReport memory() const override { return m_.memory(); }
  ToolSupport toolSupport() const override { return m_.toolSupport(); }
  ToolResult applyTool(const ToolEvent& e) override { return m_.applyTool(e); }
  void cutWallTriangles(std::vector<std::uint8_t>& out) const override { m_.cutWallTriangles(out); }
  void renderLayers(RenderLayers& out) const override { m_.renderLayers(out); }

 private:
  SimulationModel& m_;
};

bool anyModelLayer(const ViewLayers& l) {
  return l.spheres || l.nodal_points || l.constrained || l.swept_surface || l.forces || l.colliders;
}

std::string numbered(const std::string& stem, int n) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%05d.png", n);
  return stem + buf;
}

// Throws InputError for options no window is opened for.
void validateOptions(const ViewerOptions& opt) {
  if (!opt.model && !opt.factory) throw InputError("view", "model", "no model to show");
  if (opt.width < 16 || opt.height < 16) throw InputError("view", "window", "width and height must be >= 16");
  if (opt.frames < 0) throw InputError("view", "--frames", "must be >= 0");
  if (opt.camera &&
      !(std::isfinite(opt.camera->yaw_deg) && opt.camera->pitch_deg >= -89.0 && opt.camera->pitch_deg <= 89.0 &&
        opt.camera->distance_m >= 0.0 && std::isfinite(opt.camera->distance_m)))
    throw InputError("view", "--camera", "yaw finite, pitch in [-89, 89] degrees, distance >= 0 m");
}

// The window with its GL context, or nullptr after saying on stderr why there is none.
std::unique_ptr<GlWindow> openWindow(const ViewerOptions& opt) {
  GlWindowOptions wopt;
  wopt.width = opt.width;
  wopt.height = opt.height;
  wopt.vsync = opt.vsync && opt.frames == 0;  // a scripted run draws as fast as it can
  wopt.title = opt.title;
  std::string why;
  auto window = GlWindow::open(wopt, &why);
  if (!window) {
    std::fprintf(stderr,
                 "incision view: %s.\nThe viewer needs a display with OpenGL 3.3; for a headless run use "
                 "`incision run SCENE` (or xvfb-run -a incision view ...).\n",
                 why.c_str());
    return nullptr;
  }
  if (opt.verbose) std::printf("incision view: OpenGL %s\n", window->glVersion().c_str());
  return window;
}

// ImGui's context and its GLFW / OpenGL 3 backends for the window, for the scope's lifetime.
class ImGuiScope {
 public:
  explicit ImGuiScope(GLFWwindow* win) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;  // no imgui.ini litter in the working directory
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(win, true);
    ImGui_ImplOpenGL3_Init("#version 330");
  }
  ~ImGuiScope() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  ImGuiScope(const ImGuiScope&) = delete;
  ImGuiScope& operator=(const ImGuiScope&) = delete;
};

}  // namespace

ViewerApp::ViewerApp(const ViewerOptions& opt, GLFWwindow* window, SimRunner& runner)
    : opt_(opt), win_(window), runner_(runner), scripted_(opt.frames > 0), layers_(opt.layers) {
  tool_.collision = opt.collision;
  r_.tool_style.front = {0.75f, 0.78f, 0.82f};
  r_.tool_style.back = r_.tool_style.front;
  runner_.latest(snap_, version_);
  orbit_.z_up = opt.z_up;
  frameScene();
  applyCameraOption();
  uploadToolMesh();
  force_scale_m_per_n_ = opt.force_scale_m_per_n;
  layers_wanted_ = anyModelLayer(layers_);
  runner_.setLayersWanted(layers_wanted_);
  tool_.press_depth_m = opt.press_depth_m;
  tool_.mode = opt.tool_mode;
  tool_.grasp_radius_m = opt.grasp_radius_m > 0 ? opt.grasp_radius_m : 0.08 * scene_radius_;
  tool_.blade_length_m = opt.blade_length_m > 0 ? opt.blade_length_m : 2.0 * scene_radius_;
  capture_.recording = !opt.record_dir.empty();
  t_prev_ = std::chrono::steady_clock::now();
}

void ViewerApp::frameScene() {
  Vec3d lo, hi;
  if (pointBounds(snap_.has_surface ? snap_.surface.vertices : snap_.positions, lo, hi)) {
    orbit_.frameBox(lo, hi);
    scene_radius_ = std::max(0.5 * norm(hi - lo), 1e-3);
  }
}

void ViewerApp::applyCameraOption() {
  if (!opt_.camera) return;  // the framing's target, the asked angles (and distance)
  orbit_.yaw_rad = opt_.camera->yaw_deg * M_PI / 180.0;
  orbit_.pitch_rad = opt_.camera->pitch_deg * M_PI / 180.0;
  if (opt_.camera->distance_m > 0.0) orbit_.distance_m = opt_.camera->distance_m;
}

bool ViewerApp::running() const { return !glfwWindowShouldClose(win_) && (!scripted_ || frame_index_ < opt_.frames); }

void ViewerApp::frame() {
  glfwPollEvents();
  stepSimulation();
  uploadSnapshot();
  measureFrameRate();
  beginFrame();
  // Input: camera and shortcuts (unless ImGui has the mouse / keyboard).
  readPointer();
  handleCameraMouse();
  handleShortcuts();
  view_.cam = orbit_.view(view_.fb_w, view_.fb_h);  // after this frame's orbit, pan, zoom and framing
  drawScene();
  // The tool reads the scene's depth under the cursor, so it is placed after the scene is drawn.
  updateTool();
  drawOverlays();
  if (opt_.show_ui) drawPanels();
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  reportFrame();
  ++frame_index_;
  captureFrame();  // reads the back buffer before the swap
  glfwSwapBuffers(win_);
}

void ViewerApp::stepSimulation() {
  runner_.pump();
  if (anyModelLayer(layers_) != layers_wanted_) runner_.setLayersWanted(layers_wanted_ = anyModelLayer(layers_));
  if (runner_.latest(snap_, version_)) {
    need_upload_ = true;
    plots_.push(snap_);
  }
}

void ViewerApp::measureFrameRate() {
  const auto t_now = std::chrono::steady_clock::now();
  const double frame_s = std::chrono::duration<double>(t_now - t_prev_).count();
  t_prev_ = t_now;
  if (frame_s > 0) plots_.pushFrameRate(1.0 / frame_s);
}

void ViewerApp::beginFrame() {
  FrameView& v = view_;
  glfwGetFramebufferSize(win_, &v.fb_w, &v.fb_h);
  v.fb_w = std::max(v.fb_w, 1);
  v.fb_h = std::max(v.fb_h, 1);
  v.win_w = 1;
  v.win_h = 1;
  glfwGetWindowSize(win_, &v.win_w, &v.win_h);
  v.px_scale = double(v.fb_w) / std::max(v.win_w, 1);

  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
}

void ViewerApp::reportFrame() {
  if (!opt_.on_frame) return;
  ViewerFrameInfo info;
  info.index = frame_index_;
  info.sim_frame = snap_.frame;
  info.tool_on_surface = tool_.valid;
  info.tool_tip = tool_.tip;
  info.contact = tool_.contact;
  info.camera = view_.cam;
  info.force_scale_m_per_n = layers_.forces ? force_scale_used_ : 0.0;
  opt_.on_frame(info);
}

void ViewerApp::captureFrame() {
  const bool last_scripted = scripted_ && frame_index_ == opt_.frames;
  const bool final_shot = last_scripted && !opt_.screenshot_path.empty();
  if (capture_.want_shot || capture_.recording || final_shot) {
    glReadBuffer(GL_BACK);
    const RgbImage img = readFramebuffer(view_.fb_w, view_.fb_h);
    if (final_shot) writePng(opt_.screenshot_path, img);
    if (capture_.want_shot) {
      const std::string path = numbered("incision_screenshot", capture_.shot_counter++);
      writePng(path, img);
      ui_.status = "wrote " + path;
    }
    if (capture_.recording) {
      const std::string dir = opt_.record_dir.empty() ? std::string(".") : opt_.record_dir;
      writePng(numbered(dir + "/frame", capture_.record_counter++), img);
    }
  }
  capture_.want_shot = false;  // a shot is asked for (P, the button) afresh each frame
}

int runViewer(const ViewerOptions& opt) {
  validateOptions(opt);
  const std::unique_ptr<GlWindow> window = openWindow(opt);
  if (!window) return 1;

  std::unique_ptr<SimulationModel> first;
  if (opt.model) first = std::make_unique<BorrowedModel>(*opt.model);
  const bool scripted = opt.frames > 0;
  SimRunner runner(std::move(first), opt.factory, opt.knobs, opt.frame_dt_s, opt.threaded && !scripted);
  runner.setPaused(opt.start_paused);

  const ImGuiScope imgui(window->handle());
  try {
    ViewerApp app(opt, window->handle(), runner);
    while (app.running()) app.frame();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "incision view: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace inc::viewer
