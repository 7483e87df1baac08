// The viewer's ImGui panels: run controls, knobs, live plots, layers, the tool, captures, help and status bar.
#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include <imgui.h>

#include "viewer/viewer_app_internal.h"

namespace inc::viewer {

namespace {

const char* viewerBackendName(BackendKind k) {
  switch (k) {
    case BackendKind::Cuda: return "CUDA (GPU)";
    case BackendKind::Cpu: return "CPU fallback";
    default: return "auto";
  }
}

// A choice knob as a combo box; the choice is sent when picked.
void drawChoiceKnob(SimRunner& runner, std::size_t i, const ViewerKnob& k, double v) {
  int c = std::clamp(int(v), 0, int(k.choices.size()) - 1);
  bool changed = false;
  if (ImGui::BeginCombo(k.label.c_str(), k.choices[std::size_t(c)].c_str())) {
    for (std::size_t j = 0; j < k.choices.size(); ++j)
      if (ImGui::Selectable(k.choices[j].c_str(), int(j) == c)) {
        c = int(j);
        changed = true;
      }
    ImGui::EndCombo();
  }
  if (changed) runner.setKnob(i, c);
}

// A numeric knob as a slider. Knobs that rebuild the model (`edit`) send their value when the slider is
// released, not while it is dragged; until then `editing` holds the dragged value.
void drawSliderKnob(SimRunner& runner, std::size_t i, const ViewerKnob& k, double v,
                    std::map<std::size_t, double>& editing) {
  const ImGuiSliderFlags fl = k.logarithmic ? ImGuiSliderFlags_Logarithmic : 0;
  bool changed;
  if (k.integer) {
    int iv = int(v);
    changed = ImGui::SliderInt(k.label.c_str(), &iv, int(k.min_value), int(k.max_value), "%d", fl);
    v = iv;
  } else {
    changed = ImGui::SliderScalar(k.label.c_str(), ImGuiDataType_Double, &v, &k.min_value, &k.max_value, "%.4g", fl);
  }
  if (!k.edit) {
    if (changed) runner.setKnob(i, v);
    return;
  }
  if (changed) editing[i] = v;
  if (ImGui::IsItemDeactivatedAfterEdit()) runner.setKnob(i, v);
  if (!ImGui::IsItemActive()) editing.erase(i);
}

// The knobs of one panel group as sliders (combo boxes for choices).
void drawKnobs(SimRunner& runner, const std::string& group, std::map<std::size_t, double>& editing) {
  const std::vector<ViewerKnob> knobs = runner.knobs();
  for (std::size_t i = 0; i < knobs.size(); ++i) {
    const ViewerKnob& k = knobs[i];
    if (k.group != group) continue;
    auto it = editing.find(i);
    const double v = it != editing.end() ? it->second : k.value;
    if (!k.choices.empty())
      drawChoiceKnob(runner, i, k, v);
    else
      drawSliderKnob(runner, i, k, v, editing);
  }
}

constexpr const char* kHelpText =
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
    "H, F1         this help    Esc  quit";

}  // namespace

void ViewerApp::drawPanels() {
  drawMainPanel();
  if (ui_.show_help) drawHelp();
  drawStatusBar();
}

void ViewerApp::drawMainPanel() {
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(390, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("Incision");
  ImGui::PushItemWidth(170);
  drawRunControls();
  drawKnobPanels();
  if (!snap_.message.empty()) ImGui::TextColored(ImVec4(1, 0.6f, 0.3f, 1), "%s", snap_.message.c_str());
  drawPlotPanels();
  if (ImGui::CollapsingHeader("Layers")) drawLayersPanel();
  if (ImGui::CollapsingHeader("Tool", ImGuiTreeNodeFlags_DefaultOpen)) drawToolPanel();
  drawCaptureButtons();
  ImGui::PopItemWidth();
  ImGui::End();
}

// The model's name and state, pause / step / reset and the time scale.
void ViewerApp::drawRunControls() {
  ImGui::Text("%s", snap_.name.c_str());
  ImGui::Text("backend: %s   particles: %zu", viewerBackendName(snap_.backend), snap_.particles);
  ImGui::Text("frame %llu   t = %.3f s", static_cast<unsigned long long>(snap_.frame), snap_.sim_time_s);
  if (snap_.failed) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", snap_.failure.c_str());
  bool paused = runner_.paused();
  if (ImGui::Checkbox("pause (space)", &paused)) runner_.setPaused(paused);
  ImGui::SameLine();
  if (ImGui::Button("step (N)")) runner_.stepOnce();
  if (runner_.canReset()) {
    ImGui::SameLine();
    if (ImGui::Button("reset (R)")) runner_.reset();
  }
  float slow = float(runner_.timeScale());
  if (ImGui::SliderFloat("time scale", &slow, 0.01f, 1.0f, "%.2f", ImGuiSliderFlags_Logarithmic))
    runner_.setTimeScale(slow);
}

// "Speed / accuracy" (step safety and the group-less knobs), then the scene's Material, Solver and Cutting knobs.
void ViewerApp::drawKnobPanels() {
  if (ImGui::CollapsingHeader("Speed / accuracy", ImGuiTreeNodeFlags_DefaultOpen)) {
    float safety = float(runner_.stepSafety());
    if (ImGui::SliderFloat("step safety x", &safety, 0.05f, 2.0f, "%.2f", ImGuiSliderFlags_Logarithmic))
      runner_.setStepSafety(safety);
    drawKnobs(runner_, "", ui_.knob_editing);
    ImGui::Text("substeps %d   dt %.3g s", snap_.report.substeps, snap_.report.dt);
  }
  // The scene's material and solver settings (built from the loaded scene by the scene wiring).
  for (const char* group : {"Material", "Solver", "Cutting"}) {
    const std::vector<ViewerKnob> all = runner_.knobs();
    if (std::none_of(all.begin(), all.end(), [&](const ViewerKnob& k) { return k.group == group; })) continue;
    if (ImGui::CollapsingHeader(group, ImGuiTreeNodeFlags_DefaultOpen)) drawKnobs(runner_, group, ui_.knob_editing);
  }
}

void ViewerApp::drawPlotPanels() {
  if (ImGui::CollapsingHeader("Timing", ImGuiTreeNodeFlags_DefaultOpen)) plots_.drawTiming();
  if (ImGui::CollapsingHeader("Haptics")) plots_.drawHaptics();
  // Energies, particle count and the model's counters (e.g. broken_bonds) over the last frames.
  if (ImGui::CollapsingHeader("Energy and counters")) plots_.drawEnergy();
}

// The layer toggles (with their keys and sizes), the force arrows' scale and the splats' width.
void ViewerApp::drawLayersPanel() {
  const RenderLayers& rl = r_.model_layers.layers();
  ImGui::Checkbox("surface (1)", &layers_.surface);
  ImGui::SameLine();
  ImGui::Checkbox("splats (2)", &layers_.splats);
  ImGui::Checkbox("particles (3)", &layers_.particles);
  ImGui::SameLine();
  ImGui::Checkbox("wireframe (4)", &layers_.wireframe);
  ImGui::Checkbox("spheres (5)", &layers_.spheres);
  ImGui::SameLine();
  ImGui::TextDisabled("%zu", rl.sphere_centres.size());
  ImGui::SameLine();
  ImGui::Checkbox("nodal points (6)", &layers_.nodal_points);
  ImGui::SameLine();
  ImGui::TextDisabled("%zu", rl.nodal_points.size());
  ImGui::Checkbox("fixed / held (7)", &layers_.constrained);
  ImGui::SameLine();
  ImGui::TextDisabled("%zu / %zu", rl.fixed_points.size(), rl.held_points.size());
  ImGui::SameLine();
  ImGui::Checkbox("swept surface (8)", &layers_.swept_surface);
  ImGui::Checkbox("colliders (0)", &layers_.colliders);
  ImGui::SameLine();
  ImGui::Checkbox("forces (9)", &layers_.forces);
  ImGui::SameLine();
  drawForceScale(rl);
  float sf = float(r_.splat_params.sigma_fraction);
  if (ImGui::SliderFloat("splat sigma / r", &sf, 0.2f, 1.0f)) r_.splat_params.sigma_fraction = sf;
}

// The largest tool force (or the arrow count), and the arrows' scale: automatic or a slider in mm/N.
void ViewerApp::drawForceScale(const RenderLayers& rl) {
  double fmax = 0;
  for (const ForceArrow& a : rl.forces)
    if (a.kind == ForceArrowKind::Tool) fmax = std::max(fmax, norm(a.force_n));
  if (fmax > 0)
    ImGui::TextDisabled("tool %.3g N", fmax);
  else
    ImGui::TextDisabled("%zu arrows", rl.forces.size());
  bool auto_scale = force_scale_m_per_n_ <= 0;
  if (ImGui::Checkbox("auto force scale", &auto_scale))
    force_scale_m_per_n_ = auto_scale ? 0.0 : std::max(force_scale_used_, 1e-6);
  if (!auto_scale) {
    float mm_per_n = float(force_scale_m_per_n_ * 1e3);
    if (ImGui::SliderFloat("force scale [mm/N]", &mm_per_n, 1e-3f, 1e4f, "%.3g", ImGuiSliderFlags_Logarithmic))
      force_scale_m_per_n_ = mm_per_n * 1e-3;
  } else {
    ImGui::SameLine();
    ImGui::TextDisabled("%.3g mm/N", force_scale_used_ * 1e3);
  }
}

// The tool's mode, sizes, collision mode and press depth, and what it touches.
void ViewerApp::drawToolPanel() {
  drawToolModes();
  drawToolSizes();
  drawToolContact();
}

// On / off, and camera, grasp or cut (greyed out when the model cannot be grasped or cut).
void ViewerApp::drawToolModes() {
  ToolState& t = tool_;
  const ToolSupport& can = snap_.tool_support;
  ImGui::Checkbox("tool (T)", &layers_.tool);
  int tm = int(t.mode);
  ImGui::RadioButton("camera", &tm, 0);
  ImGui::SameLine();
  ImGui::BeginDisabled(!can.grasp);
  ImGui::RadioButton("grasp (G)", &tm, 1);
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(!can.cut);
  ImGui::RadioButton("cut (C)", &tm, 2);
  ImGui::EndDisabled();
  t.mode = ToolMode(tm);
  if (t.mode == ToolMode::Grasp && !can.grasp) ImGui::TextDisabled("%s cannot be grasped", snap_.name.c_str());
  if (t.mode == ToolMode::Cut && !can.cut) ImGui::TextDisabled("%s cannot be cut", snap_.name.c_str());
}

// The grasp's reach and the blade's length, what the last tool event did, and the haptic loop's force.
void ViewerApp::drawToolSizes() {
  ToolState& t = tool_;
  const ToolSupport& can = snap_.tool_support;
  float grasp_mm = float(t.grasp_radius_m * 1e3), blade_mm = float(t.blade_length_m * 1e3);
  if (ImGui::SliderFloat("grasp radius [mm]", &grasp_mm, 0.5f, float(500.0 * scene_radius_), "%.1f",
                         ImGuiSliderFlags_Logarithmic))
    t.grasp_radius_m = grasp_mm * 1e-3;
  if (ImGui::SliderFloat("blade length [mm]", &blade_mm, 1.0f, float(4000.0 * scene_radius_), "%.1f",
                         ImGuiSliderFlags_Logarithmic))
    t.blade_length_m = blade_mm * 1e-3;
  if (can.grasp || can.cut)
    ImGui::Text("held: %d%s", snap_.last_tool.grasped, snap_.last_tool.cut_applied ? "   last stroke cut" : "");
  if (opt_.haptic_pointer) {
    const Vec3d hf = opt_.haptic_pointer->displayForce();
    ImGui::Text("haptic force %.3f N (%.3f, %.3f, %.3f)", norm(hf), hf.x, hf.y, hf.z);
  }
}

// How the tip collides, how deep it presses, and where it is.
void ViewerApp::drawToolContact() {
  ToolState& t = tool_;
  int mode = t.collision == ToolCollision::DepthBuffer ? 0 : 1;
  ImGui::RadioButton("depth under cursor", &mode, 0);
  ImGui::SameLine();
  ImGui::RadioButton("z-buffer splats", &mode, 1);
  t.collision = mode == 0 ? ToolCollision::DepthBuffer : ToolCollision::SplatZBuffer;
  float press_mm = float(t.press_depth_m * 1e3);
  if (ImGui::SliderFloat("press depth [mm] (ctrl+wheel)", &press_mm, 0.0f, float(200.0 * scene_radius_)))
    t.press_depth_m = press_mm * 1e-3;
  if (t.valid)
    ImGui::Text("tip (%.4f, %.4f, %.4f) m  %s  pen %.2f mm", t.tip.x, t.tip.y, t.tip.z,
                t.contact.inside ? "INSIDE" : "outside", t.contact.penetration_m * 1e3);
  else
    ImGui::TextDisabled("tip: no surface under the cursor");
  if (t.collision == ToolCollision::SplatZBuffer && !snap_.has_surface)
    ImGui::TextDisabled("z-buffer mode needs oriented splats (a surface)");
}

void ViewerApp::drawCaptureButtons() {
  if (ImGui::Button("screenshot (P)")) capture_.want_shot = true;
  ImGui::SameLine();
  ImGui::Checkbox("record (V)", &capture_.recording);
  ImGui::SameLine();
  if (ImGui::Button("help (H)")) ui_.show_help = !ui_.show_help;
  if (!ui_.status.empty()) ImGui::TextDisabled("%s", ui_.status.c_str());
}

void ViewerApp::drawHelp() {
  ImGui::Begin("Controls", &ui_.show_help, ImGuiWindowFlags_AlwaysAutoResize);
  ImGui::TextUnformatted(kHelpText);
  ImGui::End();
}

void ViewerApp::drawStatusBar() {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(0, io.DisplaySize.y - 24));
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x, 24));
  ImGui::Begin("status", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoInputs | ImGuiWindowFlags_NoSavedSettings);
  ImGui::Text("%s | %s | %.0f fps | step %.2f ms%s", viewerBackendName(snap_.backend),
              snap_.backend == BackendKind::Cpu ? "no GPU model: running on the CPU" : "GPU",
              double(plots_.fps().last()), snap_.advance_ms, runner_.paused() ? " | PAUSED" : "");
  ImGui::End();
}

}  // namespace inc::viewer
