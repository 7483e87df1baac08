// The viewer's main loop: window, input, drawing layers, the tool under the mouse, ImGui panels, captures.
#include "viewer/viewer_app.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

#include "model/input_error.h"
#include "viewer/gl_api.h"
#include "viewer/gl_window.h"

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include "viewer/live_plots.h"
#include "viewer/model_layers.h"
#include "viewer/orbit_camera.h"
#include "viewer/screenshot.h"
#include "viewer/splat_renderer.h"
#include "viewer/splat_sources.h"
#include "viewer/surface_renderer.h"
#include "viewer/zbuffer_collision.h"
#include "viewer/zbuffer_collision_gl.h"

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

bool anyModelLayer(const ViewLayers& l) {
  return l.spheres || l.nodal_points || l.constrained || l.swept_surface || l.forces || l.colliders;
}

const char* viewerBackendName(BackendKind k) {
  switch (k) {
    case BackendKind::Cuda: return "CUDA (GPU)";
    case BackendKind::Cpu: return "CPU fallback";
    default: return "auto";
  }
}

struct Frame {
  ViewCamera cam;
  int fb_w = 1, fb_h = 1;
};

// The knobs of one panel group as sliders (combo boxes for choices). Knobs that rebuild the model send their
// value when the slider is released, not while it is dragged.
void drawKnobs(SimRunner& runner, const std::string& group, std::map<std::size_t, double>& editing) {
  const std::vector<ViewerKnob> knobs = runner.knobs();
  for (std::size_t i = 0; i < knobs.size(); ++i) {
    const ViewerKnob& k = knobs[i];
    if (k.group != group) continue;
    auto it = editing.find(i);
    double v = it != editing.end() ? it->second : k.value;
    bool changed;
    if (!k.choices.empty()) {
      int c = std::clamp(int(v), 0, int(k.choices.size()) - 1);
      changed = false;
      if (ImGui::BeginCombo(k.label.c_str(), k.choices[std::size_t(c)].c_str())) {
        for (std::size_t j = 0; j < k.choices.size(); ++j)
          if (ImGui::Selectable(k.choices[j].c_str(), int(j) == c)) {
            c = int(j);
            changed = true;
          }
        ImGui::EndCombo();
      }
      if (changed) runner.setKnob(i, c);
      continue;
    }
    const ImGuiSliderFlags fl = k.logarithmic ? ImGuiSliderFlags_Logarithmic : 0;
    if (k.integer) {
      int iv = int(v);
      changed = ImGui::SliderInt(k.label.c_str(), &iv, int(k.min_value), int(k.max_value), "%d", fl);
      v = iv;
    } else {
      changed = ImGui::SliderScalar(k.label.c_str(), ImGuiDataType_Double, &v, &k.min_value, &k.max_value, "%.4g", fl);
    }
    if (!k.edit) {
      if (changed) runner.setKnob(i, v);
      continue;
    }
    if (changed) editing[i] = v;
    if (ImGui::IsItemDeactivatedAfterEdit()) runner.setKnob(i, v);
    if (!ImGui::IsItemActive()) editing.erase(i);
  }
}

std::string numbered(const std::string& stem, int n) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%05d.png", n);
  return stem + buf;
}

}  // namespace

int runViewer(const ViewerOptions& opt) {
  if (!opt.model && !opt.factory) throw InputError("view", "model", "no model to show");
  if (opt.width < 16 || opt.height < 16) throw InputError("view", "window", "width and height must be >= 16");
  if (opt.frames < 0) throw InputError("view", "--frames", "must be >= 0");
  if (opt.camera && !(std::isfinite(opt.camera->yaw_deg) && opt.camera->pitch_deg >= -89.0 && opt.camera->pitch_deg <= 89.0 &&
                      opt.camera->distance_m >= 0.0 && std::isfinite(opt.camera->distance_m)))
    throw InputError("view", "--camera", "yaw finite, pitch in [-89, 89] degrees, distance >= 0 m");

  GlWindowOptions wopt;
  wopt.width = opt.width;
  wopt.height = opt.height;
  wopt.vsync = opt.vsync && opt.frames == 0;
  wopt.title = opt.title;
  std::string why;
  auto window = GlWindow::open(wopt, &why);
  if (!window) {
    std::fprintf(stderr,
                 "incision view: %s.\nThe viewer needs a display with OpenGL 3.3; for a headless run use "
                 "`incision run SCENE` (or xvfb-run -a incision view ...).\n",
                 why.c_str());
    return 1;
  }
  GLFWwindow* win = window->handle();
  if (opt.verbose) std::printf("incision view: OpenGL %s\n", window->glVersion().c_str());

  std::unique_ptr<SimulationModel> first;
  if (opt.model) first = std::make_unique<BorrowedModel>(*opt.model);
  const bool scripted = opt.frames > 0;
  SimRunner runner(std::move(first), opt.factory, opt.knobs, opt.frame_dt_s, opt.threaded && !scripted);
  runner.setPaused(opt.start_paused);

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini litter in the working directory
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(win, true);
  ImGui_ImplOpenGL3_Init("#version 330");

  int rc = 0;
  try {
    SurfaceRenderer surface, tool;
    SplatRenderer surface_splats, particle_splats;
    ModelLayerRenderer model_layers;
    ZBufferCollider collider;
    ViewLayers layers = opt.layers;
    ToolCollision collision = opt.collision;
    SurfaceStyle style;
    SurfaceStyle tool_style;
    tool_style.front = {0.75f, 0.78f, 0.82f};
    tool_style.back = tool_style.front;
    SplatParams splat_params;

    SimSnapshot snap;
    std::uint64_t version = 0;
    runner.latest(snap, version);
    OrbitCamera orbit;
    orbit.z_up = opt.z_up;
    double scene_radius = 0.1;
    auto frameScene = [&] {
      Vec3d lo, hi;
      if (pointBounds(snap.has_surface ? snap.surface.vertices : snap.positions, lo, hi)) {
        orbit.frameBox(lo, hi);
        scene_radius = std::max(0.5 * norm(hi - lo), 1e-3);
      }
    };
    frameScene();
    if (opt.camera) {  // the framing's target, the asked angles (and distance)
      orbit.yaw_rad = opt.camera->yaw_deg * M_PI / 180.0;
      orbit.pitch_rad = opt.camera->pitch_deg * M_PI / 180.0;
      if (opt.camera->distance_m > 0.0) orbit.distance_m = opt.camera->distance_m;
    }
    tool.upload([&] {
      TriangleMesh m;  // unit octahedron refined by normalising: a small sphere for the tool tip
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
    }());

    SplatCloud particle_cloud;
    bool need_upload = true;
    LivePlots plots;
    double force_scale_m_per_n = opt.force_scale_m_per_n;  // fixed scale; 0: automatic
    double force_scale_used = 0.0;
    bool layers_wanted = anyModelLayer(layers);
    runner.setLayersWanted(layers_wanted);
    double press_depth_m = opt.press_depth_m;
    ToolMode tool_mode = opt.tool_mode;
    double grasp_radius_m = opt.grasp_radius_m > 0 ? opt.grasp_radius_m : 0.08 * scene_radius;
    double blade_length_m = opt.blade_length_m > 0 ? opt.blade_length_m : 2.0 * scene_radius;
    bool tool_active = false;     // the left button is down in grasp / cut mode and an event was sent
    ToolKind active_kind = ToolKind::Grasp;  // of the press (a mode switch mid-drag still releases it)
    double tool_view_depth = 0;   // m, the pressed tip's view depth: the drag moves the tip in that plane
    Vec3d tool_sent;              // the last tip sent
    std::map<std::size_t, double> knob_editing;  // rebuild knobs: the slider's value until released
    bool show_help = false, recording = !opt.record_dir.empty();
    int shot_counter = 0, record_counter = 0, frame_index = 0;
    double last_x = 0, last_y = 0;
    ZContact contact;
    bool tool_valid = false;
    Vec3d tool_tip, surface_hit;   // the tip, and the drawn surface under the cursor (when the tip is on it)
    double haptic_shift_m = 0.0;   // pointer pose = tip + plane normal x this (frozen while a drag is held)
    bool tip_on_surface = false;   // this frame's tip is surface_hit pressed in by press_depth_m
    std::string status;
    auto t_prev = std::chrono::steady_clock::now();

    while (!glfwWindowShouldClose(win) && (!scripted || frame_index < opt.frames)) {
      glfwPollEvents();
      runner.pump();
      if (anyModelLayer(layers) != layers_wanted) runner.setLayersWanted(layers_wanted = anyModelLayer(layers));
      if (runner.latest(snap, version)) {
        need_upload = true;
        plots.push(snap);
      }
      if (need_upload) {
        if (snap.has_surface) {
          surface.upload(snap.surface, snap.cut_walls);
          surface_splats.upload(surfaceSplats(snap.surface, style.front));
        }
        particle_cloud = particleSplats(snap.positions, opt.particle_radius_m, {0.35f, 0.55f, 0.85f});
        particle_splats.upload(particle_cloud);
        model_layers.upload(snap.layers, particle_cloud.radii.empty() ? 0.0 : 1.15 * particle_cloud.radii.front());
        need_upload = false;
      }
      const auto t_now = std::chrono::steady_clock::now();
      const double frame_s = std::chrono::duration<double>(t_now - t_prev).count();
      t_prev = t_now;
      if (frame_s > 0) plots.pushFrameRate(1.0 / frame_s);

      Frame f;
      glfwGetFramebufferSize(win, &f.fb_w, &f.fb_h);
      f.fb_w = std::max(f.fb_w, 1);
      f.fb_h = std::max(f.fb_h, 1);
      int win_w = 1, win_h = 1;
      glfwGetWindowSize(win, &win_w, &win_h);
      const double px_scale = double(f.fb_w) / std::max(win_w, 1);

      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();

      // --- input: camera and shortcuts (unless ImGui has the mouse/keyboard) ---
      double mx, my;
      glfwGetCursorPos(win, &mx, &my);
      bool scripted_cursor = opt.cursor_x >= 0.0 && opt.cursor_y >= 0.0;
      if (scripted_cursor) {
        mx = opt.cursor_x * win_w;
        my = opt.cursor_y * win_h;
      }
      bool scripted_down = false;
      if (opt.scripted_mouse) {
        double sx = -1, sy = -1;
        scripted_down = opt.scripted_mouse(frame_index, sx, sy);
        if (sx >= 0.0 && sy >= 0.0) {
          scripted_cursor = true;
          mx = sx * win_w;
          my = sy * win_h;
        }
      }
      if (!io.WantCaptureMouse) {
        const double dx = mx - last_x, dy = my - last_y;
        const bool shift = glfwGetKey(win, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS;
        const bool alt = glfwGetKey(win, GLFW_KEY_LEFT_ALT) == GLFW_PRESS;
        // In grasp / cut mode the left button belongs to the tool; alt + left or the middle button orbit.
        const bool left_orbits = tool_mode == ToolMode::Camera || alt;
        if ((glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS && !shift && left_orbits && !tool_active) ||
            glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS)
          orbit.orbit(dx, dy);
        if (glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
            (glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS && shift))
          orbit.pan(dx * px_scale, dy * px_scale, f.fb_h);
        if (io.MouseWheel != 0.0f) {
          if (glfwGetKey(win, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS)
            press_depth_m = std::max(0.0, press_depth_m + 0.02 * scene_radius * io.MouseWheel);
          else
            orbit.zoom(std::pow(0.9, double(io.MouseWheel)));
        }
      }
      last_x = mx;
      last_y = my;
      bool want_shot = false;
      if (!io.WantCaptureKeyboard) {
        if (ImGui::IsKeyPressed(GLFW_KEY_SPACE)) runner.setPaused(!runner.paused());
        if (ImGui::IsKeyPressed(GLFW_KEY_N)) runner.stepOnce();
        if (ImGui::IsKeyPressed(GLFW_KEY_R)) runner.reset();
        if (ImGui::IsKeyPressed(GLFW_KEY_F)) frameScene();
        if (ImGui::IsKeyPressed(GLFW_KEY_P)) want_shot = true;
        if (ImGui::IsKeyPressed(GLFW_KEY_V)) recording = !recording;
        if (ImGui::IsKeyPressed(GLFW_KEY_H) || ImGui::IsKeyPressed(GLFW_KEY_F1)) show_help = !show_help;
        if (ImGui::IsKeyPressed(GLFW_KEY_1)) layers.surface = !layers.surface;
        if (ImGui::IsKeyPressed(GLFW_KEY_2)) layers.splats = !layers.splats;
        if (ImGui::IsKeyPressed(GLFW_KEY_3)) layers.particles = !layers.particles;
        if (ImGui::IsKeyPressed(GLFW_KEY_4)) layers.wireframe = !layers.wireframe;
        if (ImGui::IsKeyPressed(GLFW_KEY_5)) layers.spheres = !layers.spheres;
        if (ImGui::IsKeyPressed(GLFW_KEY_6)) layers.nodal_points = !layers.nodal_points;
        if (ImGui::IsKeyPressed(GLFW_KEY_7)) layers.constrained = !layers.constrained;
        if (ImGui::IsKeyPressed(GLFW_KEY_8)) layers.swept_surface = !layers.swept_surface;
        if (ImGui::IsKeyPressed(GLFW_KEY_9)) layers.forces = !layers.forces;
        if (ImGui::IsKeyPressed(GLFW_KEY_0)) layers.colliders = !layers.colliders;
        if (ImGui::IsKeyPressed(GLFW_KEY_T)) layers.tool = !layers.tool;
        if (ImGui::IsKeyPressed(GLFW_KEY_G)) tool_mode = tool_mode == ToolMode::Grasp ? ToolMode::Camera : ToolMode::Grasp;
        if (ImGui::IsKeyPressed(GLFW_KEY_C)) tool_mode = tool_mode == ToolMode::Cut ? ToolMode::Camera : ToolMode::Cut;
        if (ImGui::IsKeyPressed(GLFW_KEY_MINUS)) runner.setTimeScale(runner.timeScale() * 0.5);
        if (ImGui::IsKeyPressed(GLFW_KEY_EQUAL)) runner.setTimeScale(runner.timeScale() * 2.0);
        if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE)) glfwSetWindowShouldClose(win, GLFW_TRUE);
      }

      // --- the scene ---
      f.cam = orbit.view(f.fb_w, f.fb_h);
      glBindFramebuffer(GL_FRAMEBUFFER, 0);
      glViewport(0, 0, f.fb_w, f.fb_h);
      glDepthMask(GL_TRUE);
      glClearColor(0.11f, 0.12f, 0.14f, 1.0f);
      glClearDepth(1.0);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
      style.wireframe = layers.wireframe;
      if (snap.has_surface && layers.surface && !layers.splats) surface.draw(f.cam, style);
      if (snap.has_surface && layers.splats) surface_splats.draw(f.cam, splat_params);
      const ModelLayerToggles toggles = modelToggles(layers);
      // Marked particles (fixed, held, nodal) before the plain particle splats, so that they show over them.
      model_layers.drawOpaque(f.cam, toggles, splat_params);
      if (layers.particles || !snap.has_surface) particle_splats.draw(f.cam, splat_params);
      model_layers.drawTranslucent(f.cam, toggles);

      // --- the tool under the mouse: z-buffer depth under the cursor places it on the drawn surface ---
      tool_valid = false;
      tip_on_surface = false;
      contact = ZContact{};
      const double cx = mx * px_scale, cy = f.fb_h - my * px_scale;  // GL pixels, origin bottom-left
      if (layers.tool && (scripted_cursor || !io.WantCaptureMouse) && cx >= 0 && cy >= 0 && cx < f.fb_w && cy < f.fb_h) {
        const std::vector<float> d = readDepth(int(cx), int(cy), 1, 1);
        Vec3d hit;
        if (pointFromWindowDepth(f.cam, std::floor(cx) + 0.5, std::floor(cy) + 0.5, d[0], hit)) {
          Vec3d o, dir;
          f.cam.pixelRay(std::floor(cx) + 0.5, std::floor(cy) + 0.5, o, dir);
          tool_tip = hit + dir * press_depth_m;
          surface_hit = hit;
          tool_valid = tip_on_surface = true;
          if (collision == ToolCollision::SplatZBuffer) {
            const ViewCamera zc = cameraRayDepthCamera(f.cam.eye, tool_tip, 0.01 * scene_radius, f.cam.far_m, 33);
            // The paper's GPU z-buffer test needs oriented splats: the surface's (view-facing particle
            // discs have no back side, so nothing would ever count as inside).
            if (snap.has_surface) contact = collider.collide(zc, surface_splats, tool_tip);
            else contact = ZContact{};
          } else {
            contact = ZContact{};
            contact.inside = press_depth_m > 0.0;
            contact.surface_point = hit;
            contact.penetration_m = press_depth_m;
          }
        }
      }
      // --- grasp / cut: press, drag and release become tool events for the simulation thread ---
      {
        const bool supported = tool_mode == ToolMode::Grasp ? snap.tool_support.grasp
                               : tool_mode == ToolMode::Cut ? snap.tool_support.cut
                                                            : false;
        const bool alt = glfwGetKey(win, GLFW_KEY_LEFT_ALT) == GLFW_PRESS;
        const bool down = opt.scripted_mouse ? scripted_down
                                             : glfwGetMouseButton(win, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS && !alt;
        // Off the organ a stroke (or a grasp) starts in the view plane through the orbit target, so a cut can
        // begin outside the tissue like a real scalpel's.
        if (supported && !tool_active && !tool_valid && cx >= 0 && cy >= 0 && cx < f.fb_w && cy < f.fb_h) {
          Vec3d o, dir;
          f.cam.pixelRay(cx, cy, o, dir);
          const double along = dot(dir, f.cam.forward);
          if (along > 1e-9) {
            tool_tip = o + dir * ((f.cam.viewDepth(orbit.target) - dot(o - f.cam.eye, f.cam.forward)) / along);
            tool_valid = true;
          }
        }
        // In a haptics scene the haptic cutting tool cuts: the mouse stroke only moves its blade.
        auto send = [&](const ToolEvent& e) {
          if (!(opt.haptic_pointer && e.kind == ToolKind::Cut)) runner.queueTool(e);
        };
        ToolEvent ev;
        ev.kind = tool_active ? active_kind : tool_mode == ToolMode::Cut ? ToolKind::Cut : ToolKind::Grasp;
        ev.axis = f.cam.forward;
        ev.radius_m = grasp_radius_m;
        ev.blade_length_m = blade_length_m;
        if (tool_active && cx >= 0 && cy >= 0) {
          // The dragged tip stays in the view plane of the press (under the cursor, at the pressed depth).
          Vec3d o, dir;
          f.cam.pixelRay(cx, cy, o, dir);
          const double along = dot(dir, f.cam.forward);
          if (along > 1e-9) {
            tool_tip = o + dir * ((tool_view_depth - dot(o - f.cam.eye, f.cam.forward)) / along);
            tool_valid = true;
          }
        }
        if (supported && down && !tool_active && tool_valid && (scripted_cursor || !io.WantCaptureMouse)) {
          tool_active = true;
          active_kind = ev.kind;
          tool_view_depth = f.cam.viewDepth(tool_tip);
          ev.phase = ToolPhase::Press;
          ev.tip = tool_sent = tool_tip;
          send(ev);
        } else if (tool_active && (down && supported)) {
          if (norm(tool_tip - tool_sent) > 1e-3 * scene_radius) {
            ev.phase = ToolPhase::Drag;
            ev.tip = tool_sent = tool_tip;
            send(ev);
          }
        } else if (tool_active) {
          ev.phase = ToolPhase::Release;
          ev.tip = tool_sent = tool_tip;
          send(ev);
          tool_active = false;
        }
        // The haptic pointer: the tip's pose every frame, pressed into the tissue plane by the press depth.
        if (opt.haptic_pointer && tool_valid) {
          const Vec3d& n = opt.haptic_plane_normal;
          if (!tool_active && tip_on_surface) haptic_shift_m = dot(opt.haptic_plane_point_m - surface_hit, n);
          const double identity[4] = {1.0, 0.0, 0.0, 0.0};
          opt.haptic_pointer->setPose(tool_tip + n * haptic_shift_m, identity, down ? 1u : 0u);
        }
      }
      force_scale_used = forceArrowScale(model_layers.layers().forces, force_scale_m_per_n, scene_radius);
      model_layers.drawForces(f.cam, toggles, force_scale_used);
      if (tool_valid) {
        const double r = 0.03 * scene_radius;
        tool_style.front = tool_active ? std::array<float, 3>{0.95f, 0.8f, 0.2f}
                           : contact.inside ? std::array<float, 3>{0.3f, 0.85f, 0.4f}
                                            : std::array<float, 3>{0.75f, 0.78f, 0.82f};
        tool_style.back = tool_style.front;
        tool_style.on_top = true;  // the tip stays visible when pressed into the tissue
        const Mat4f model = frameMatrix({r, 0, 0}, {0, r, 0}, {0, 0, r}, tool_tip);
        tool.draw(f.cam, tool_style, model);
        if (tool_mode == ToolMode::Grasp && snap.tool_support.grasp) {  // the grasp's reach, as a wire ball
          const double g = grasp_radius_m;
          SurfaceStyle reach = tool_style;
          reach.wireframe = true;
          reach.on_top = false;
          tool.draw(f.cam, reach, frameMatrix({g, 0, 0}, {0, g, 0}, {0, 0, g}, tool_tip));
        }
      }

      // --- panels ---
      if (opt.show_ui) {
        ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
        ImGui::SetNextWindowSize(ImVec2(390, 0), ImGuiCond_FirstUseEver);
        ImGui::Begin("Incision");
        ImGui::PushItemWidth(170);
        ImGui::Text("%s", snap.name.c_str());
        ImGui::Text("backend: %s   particles: %zu", viewerBackendName(snap.backend), snap.particles);
        ImGui::Text("frame %llu   t = %.3f s", static_cast<unsigned long long>(snap.frame), snap.sim_time_s);
        if (snap.failed) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", snap.failure.c_str());
        bool paused = runner.paused();
        if (ImGui::Checkbox("pause (space)", &paused)) runner.setPaused(paused);
        ImGui::SameLine();
        if (ImGui::Button("step (N)")) runner.stepOnce();
        if (runner.canReset()) {
          ImGui::SameLine();
          if (ImGui::Button("reset (R)")) runner.reset();
        }
        float slow = float(runner.timeScale());
        if (ImGui::SliderFloat("time scale", &slow, 0.01f, 1.0f, "%.2f", ImGuiSliderFlags_Logarithmic))
          runner.setTimeScale(slow);
        if (ImGui::CollapsingHeader("Speed / accuracy", ImGuiTreeNodeFlags_DefaultOpen)) {
          float safety = float(runner.stepSafety());
          if (ImGui::SliderFloat("step safety x", &safety, 0.05f, 2.0f, "%.2f", ImGuiSliderFlags_Logarithmic))
            runner.setStepSafety(safety);
          drawKnobs(runner, "", knob_editing);
          ImGui::Text("substeps %d   dt %.3g s", snap.report.substeps, snap.report.dt);
        }
        // The scene's material and solver settings (built from the loaded scene by the scene wiring).
        for (const char* group : {"Material", "Solver", "Cutting"}) {
          const std::vector<ViewerKnob> all = runner.knobs();
          if (std::none_of(all.begin(), all.end(), [&](const ViewerKnob& k) { return k.group == group; })) continue;
          if (ImGui::CollapsingHeader(group, ImGuiTreeNodeFlags_DefaultOpen)) drawKnobs(runner, group, knob_editing);
        }
        if (!snap.message.empty()) ImGui::TextColored(ImVec4(1, 0.6f, 0.3f, 1), "%s", snap.message.c_str());
        if (ImGui::CollapsingHeader("Timing", ImGuiTreeNodeFlags_DefaultOpen)) plots.drawTiming();
        if (ImGui::CollapsingHeader("Haptics")) plots.drawHaptics();
        // Energies, particle count and the model's counters (e.g. broken_bonds) over the last frames.
        if (ImGui::CollapsingHeader("Energy and counters")) plots.drawEnergy();
        if (ImGui::CollapsingHeader("Layers")) {
          const RenderLayers& rl = model_layers.layers();
          ImGui::Checkbox("surface (1)", &layers.surface);
          ImGui::SameLine();
          ImGui::Checkbox("splats (2)", &layers.splats);
          ImGui::Checkbox("particles (3)", &layers.particles);
          ImGui::SameLine();
          ImGui::Checkbox("wireframe (4)", &layers.wireframe);
          ImGui::Checkbox("spheres (5)", &layers.spheres);
          ImGui::SameLine();
          ImGui::TextDisabled("%zu", rl.sphere_centres.size());
          ImGui::SameLine();
          ImGui::Checkbox("nodal points (6)", &layers.nodal_points);
          ImGui::SameLine();
          ImGui::TextDisabled("%zu", rl.nodal_points.size());
          ImGui::Checkbox("fixed / held (7)", &layers.constrained);
          ImGui::SameLine();
          ImGui::TextDisabled("%zu / %zu", rl.fixed_points.size(), rl.held_points.size());
          ImGui::SameLine();
          ImGui::Checkbox("swept surface (8)", &layers.swept_surface);
          ImGui::Checkbox("colliders (0)", &layers.colliders);
          ImGui::SameLine();
          ImGui::Checkbox("forces (9)", &layers.forces);
          ImGui::SameLine();
          double fmax = 0;
          for (const ForceArrow& a : rl.forces)
            if (a.kind == ForceArrowKind::Tool) fmax = std::max(fmax, norm(a.force_n));
          if (fmax > 0) ImGui::TextDisabled("tool %.3g N", fmax);
          else ImGui::TextDisabled("%zu arrows", rl.forces.size());
          bool auto_scale = force_scale_m_per_n <= 0;
          if (ImGui::Checkbox("auto force scale", &auto_scale))
            force_scale_m_per_n = auto_scale ? 0.0 : std::max(force_scale_used, 1e-6);
          if (!auto_scale) {
            float mm_per_n = float(force_scale_m_per_n * 1e3);
            if (ImGui::SliderFloat("force scale [mm/N]", &mm_per_n, 1e-3f, 1e4f, "%.3g", ImGuiSliderFlags_Logarithmic))
              force_scale_m_per_n = mm_per_n * 1e-3;
          } else {
            ImGui::SameLine();
            ImGui::TextDisabled("%.3g mm/N", force_scale_used * 1e3);
          }
          float sf = float(splat_params.sigma_fraction);
          if (ImGui::SliderFloat("splat sigma / r", &sf, 0.2f, 1.0f)) splat_params.sigma_fraction = sf;
        }
        if (ImGui::CollapsingHeader("Tool", ImGuiTreeNodeFlags_DefaultOpen)) {
          ImGui::Checkbox("tool (T)", &layers.tool);
          int tm = int(tool_mode);
          ImGui::RadioButton("camera", &tm, 0);
          ImGui::SameLine();
          ImGui::BeginDisabled(!snap.tool_support.grasp);
          ImGui::RadioButton("grasp (G)", &tm, 1);
          ImGui::EndDisabled();
          ImGui::SameLine();
          ImGui::BeginDisabled(!snap.tool_support.cut);
          ImGui::RadioButton("cut (C)", &tm, 2);
          ImGui::EndDisabled();
          tool_mode = ToolMode(tm);
          if (tool_mode == ToolMode::Grasp && !snap.tool_support.grasp)
            ImGui::TextDisabled("%s cannot be grasped", snap.name.c_str());
          if (tool_mode == ToolMode::Cut && !snap.tool_support.cut)
            ImGui::TextDisabled("%s cannot be cut", snap.name.c_str());
          float grasp_mm = float(grasp_radius_m * 1e3), blade_mm = float(blade_length_m * 1e3);
          if (ImGui::SliderFloat("grasp radius [mm]", &grasp_mm, 0.5f, float(500.0 * scene_radius), "%.1f",
                                 ImGuiSliderFlags_Logarithmic))
            grasp_radius_m = grasp_mm * 1e-3;
          if (ImGui::SliderFloat("blade length [mm]", &blade_mm, 1.0f, float(4000.0 * scene_radius), "%.1f",
                                 ImGuiSliderFlags_Logarithmic))
            blade_length_m = blade_mm * 1e-3;
          if (snap.tool_support.grasp || snap.tool_support.cut)
            ImGui::Text("held: %d%s", snap.last_tool.grasped, snap.last_tool.cut_applied ? "   last stroke cut" : "");
          if (opt.haptic_pointer) {
            const Vec3d hf = opt.haptic_pointer->displayForce();
            ImGui::Text("haptic force %.3f N (%.3f, %.3f, %.3f)", norm(hf), hf.x, hf.y, hf.z);
          }
          int mode = collision == ToolCollision::DepthBuffer ? 0 : 1;
          ImGui::RadioButton("depth under cursor", &mode, 0);
          ImGui::SameLine();
          ImGui::RadioButton("z-buffer splats", &mode, 1);
          collision = mode == 0 ? ToolCollision::DepthBuffer : ToolCollision::SplatZBuffer;
          float press_mm = float(press_depth_m * 1e3);
          if (ImGui::SliderFloat("press depth [mm] (ctrl+wheel)", &press_mm, 0.0f, float(200.0 * scene_radius)))
            press_depth_m = press_mm * 1e-3;
          if (tool_valid)
            ImGui::Text("tip (%.4f, %.4f, %.4f) m  %s  pen %.2f mm", tool_tip.x, tool_tip.y, tool_tip.z,
                        contact.inside ? "INSIDE" : "outside", contact.penetration_m * 1e3);
          else
            ImGui::TextDisabled("tip: no surface under the cursor");
          if (collision == ToolCollision::SplatZBuffer && !snap.has_surface)
            ImGui::TextDisabled("z-buffer mode needs oriented splats (a surface)");
        }
        if (ImGui::Button("screenshot (P)")) want_shot = true;
        ImGui::SameLine();
        ImGui::Checkbox("record (V)", &recording);
        ImGui::SameLine();
        if (ImGui::Button("help (H)")) show_help = !show_help;
        if (!status.empty()) ImGui::TextDisabled("%s", status.c_str());
        ImGui::PopItemWidth();
        ImGui::End();

        if (show_help) {
          ImGui::Begin("Controls", &show_help, ImGuiWindowFlags_AlwaysAutoResize);
          ImGui::TextUnformatted(
              "left drag     orbit\n"
              "right drag    pan (or shift + left drag)\n"
              "wheel         zoom\n"
              "ctrl + wheel  tool press depth\n"
              "space         pause / run\n"
              "N             single step\n"
              "R             reset\n"
              "- / =         slower / faster (time scale)\n"
              "1 2 3 4       surface / splats / particles / wireframe\n"
              "5 6 7 8 9     spheres / nodal points / fixed+held /\n"
              "              swept surface / forces\n"
              "T             tool on / off\n"
              "G / C         grasp / cut mode (left drag uses the tool;\n"
              "              alt + left or middle drag orbits)\n"
              "F             frame the model\n"
              "P             screenshot   V  record frames\n"
              "H, F1         this help    Esc  quit");
          ImGui::End();
        }
        // Status bar.
        ImGui::SetNextWindowPos(ImVec2(0, io.DisplaySize.y - 24));
        ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x, 24));
        ImGui::Begin("status", nullptr,
                     ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoInputs | ImGuiWindowFlags_NoSavedSettings);
        ImGui::Text("%s | %s | %.0f fps | step %.2f ms%s", viewerBackendName(snap.backend),
                    snap.backend == BackendKind::Cpu ? "no GPU model: running on the CPU" : "GPU",
                    double(plots.fps().last()), snap.advance_ms, runner.paused() ? " | PAUSED" : "");
        ImGui::End();
      }
      ImGui::Render();
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

      if (opt.on_frame) {
        ViewerFrameInfo info;
        info.index = frame_index;
        info.sim_frame = snap.frame;
        info.tool_on_surface = tool_valid;
        info.tool_tip = tool_tip;
        info.contact = contact;
        info.camera = f.cam;
        info.force_scale_m_per_n = layers.forces ? force_scale_used : 0.0;
        opt.on_frame(info);
      }
      // --- captures read the back buffer before the swap ---
      ++frame_index;
      const bool last_scripted = scripted && frame_index == opt.frames;
      if (want_shot || recording || (last_scripted && !opt.screenshot_path.empty())) {
        glReadBuffer(GL_BACK);
        const RgbImage img = readFramebuffer(f.fb_w, f.fb_h);
        if (last_scripted && !opt.screenshot_path.empty()) writePng(opt.screenshot_path, img);
        if (want_shot) {
          const std::string path = numbered("incision_screenshot", shot_counter++);
          writePng(path, img);
          status = "wrote " + path;
        }
        if (recording) {
          const std::string dir = opt.record_dir.empty() ? std::string(".") : opt.record_dir;
          writePng(numbered(dir + "/frame", record_counter++), img);
        }
      }
      glfwSwapBuffers(win);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "incision view: %s\n", e.what());
    rc = 1;
  }
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  return rc;
}

}  // namespace inc::viewer
