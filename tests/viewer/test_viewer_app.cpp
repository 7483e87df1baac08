// The whole viewer in a real window (xvfb-run -a with Mesa): scripted frames, screenshot contents, recording.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <stb_image.h>

#include "host/io/mesh.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "host/sim/dissection_simulation.h"
#include "host/sim/metaball_simulation.h"
#include "model/input_error.h"
#include "test_paths.h"
#include "tests/support/cut_block_scene.h"
#include "tests/support/repo_paths.h"
#include "tests/support/viewer_test_model.h"
#include "viewer/gl_window.h"
#include "viewer/orbit_camera.h"
#include "viewer/scene_knobs.h"
#include "viewer/viewer_app.h"

namespace inc::viewer {
namespace {

using testing::SaggingBall;

bool displayAvailable(std::string& why) {
  GlWindowOptions o;
  o.width = o.height = 32;
  o.visible = false;
  return GlWindow::open(o, &why) != nullptr;
}

struct Png {
  int w = 0, h = 0;
  std::vector<unsigned char> rgb;
};

Png loadPng(const std::string& path) {
  Png p;
  int n = 0;
  unsigned char* data = stbi_load(path.c_str(), &p.w, &p.h, &n, 3);
  if (data) {
    p.rgb.assign(data, data + std::size_t(p.w) * p.h * 3);
    stbi_image_free(data);
  }
  return p;
}

// Tissue colour: clearly red (the Phong-lit front colour is (0.80, 0.36, 0.33) times the light).
double tissueFraction(const Png& p) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < p.rgb.size(); i += 3)
    if (p.rgb[i] > p.rgb[i + 1] + 25 && p.rgb[i] > p.rgb[i + 2] + 25) ++n;
  return double(n) / (double(p.w) * p.h);
}

std::string outPath(const std::string& name) { return std::string(INCISION_BINARY_DIR) + "/" + name; }

class ViewerApp : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!displayAvailable(why)) GTEST_SKIP() << "no display (run under xvfb-run -a): " << why;
  }
};

// Cut-wall colour: the back-face colour (0.55, 0.10, 0.12) has red/green 5.5; the tissue's lit colour at most
// 0.80 / 0.36 = 2.2 (specular only lowers it). Count clearly cut-wall pixels.
double cutWallFraction(const Png& p) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < p.rgb.size(); i += 3)
    if (p.rgb[i] > 50 && p.rgb[i] >= 3.5 * p.rgb[i + 1]) ++n;
  return double(n) / (double(p.w) * p.h);
}

// A cut scene shows the cut wall colour through the opening; the intact organ shows none.
TEST_F(ViewerApp, CutSceneShowsCutWallColour) {
  for (bool cut : {false, true}) {
    ViewerOptions o;
    if (cut)
      o.model = std::make_unique<testing::CutBall>(0.05);
    else
      o.model = std::make_unique<SaggingBall>();
    o.width = 960;
    o.height = 600;
    o.frames = 6;
    o.screenshot_path = outPath(cut ? "viewer_test_cut.png" : "viewer_test_uncut.png");
    ASSERT_EQ(runViewer(o), 0);
    const Png p = loadPng(o.screenshot_path);
    ASSERT_EQ(p.w, 960);
    if (cut) {
      EXPECT_GT(cutWallFraction(p), 0.01);
    } else {
      EXPECT_LT(cutWallFraction(p), 1e-4);
    }
    EXPECT_GT(tissueFraction(p), 0.03);
  }
}

// A real dissection model (a 6 x 4 x 3 cm block of 1 cm metaballs, the half at y < 2 mm held) cut by a
// mouse-style scalpel stroke through the tool API: the free half falls away and the held half's cut wall
// (flagged by cutWallTriangles, facing +y, towards the default camera) shows in the cut-wall colour; the same
// scene without the cut shows none.
TEST_F(ViewerApp, RealCutSceneShowsCutWallColour) {
  for (bool cut : {false, true}) {
    Scene s = cuttest::dissectionBlock("<test:viewer_cut_block>", true);
    s.fixed = {{Vec3d(-1, -1, -1), Vec3d(1, 0.002, 1)}};
    s.tools = {cuttest::parkedScalpel()};  // the scene's scripted scalpel never runs here
    std::unique_ptr<SimulationModel> m =
        makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
    if (cut) {
      ToolEvent e;
      e.kind = ToolKind::Cut;
      e.axis = Vec3d(0, 0, -1);
      e.blade_length_m = 0.08;
      for (int k = 0; k <= 4; ++k) {
        e.phase = k == 0 ? ToolPhase::Press : k == 4 ? ToolPhase::Release : ToolPhase::Drag;
        e.tip = Vec3d(-0.05 + 0.025 * k, 0.002, 0.0);
        ASSERT_TRUE(m->applyTool(e).supported);
      }
    }
    for (int f = 0; f < 6; ++f) ASSERT_TRUE(m->advance(1.0 / 60.0).finite);  // the free half falls ~5 cm
    ViewerOptions o;
    o.model = std::move(m);
    o.width = 640;
    o.height = 400;
    o.frames = 3;
    o.show_ui = false;
    o.screenshot_path = outPath(cut ? "viewer_test_real_cut.png" : "viewer_test_real_uncut.png");
    ASSERT_EQ(runViewer(o), 0);
    const Png p = loadPng(o.screenshot_path);
    ASSERT_EQ(p.w, 640);
    if (cut)
      EXPECT_GT(cutWallFraction(p), 0.01);
    else
      EXPECT_LT(cutWallFraction(p), 1e-4);
    EXPECT_GT(tissueFraction(p), 0.03);
  }
}

// A 6 x 4 x 3 cm dissection block (1 cm metaballs), no gravity; its scripted scalpel never runs (t >= 100 s).
std::unique_ptr<SimulationModel> dissectionBlock() {
  Scene s = cuttest::dissectionBlock("<test:viewer_mouse_block>");
  s.tools = {cuttest::parkedScalpel()};
  return makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
}

// The viewer's own mouse path in cut mode: the button goes down left of the block (off the tissue: the stroke
// starts in the target's view plane), the cursor sweeps across the middle of the window and the button comes
// up right of it. The model then holds the cut: two sphere-graph components.
TEST_F(ViewerApp, MouseStrokeInCutModeCutsTheModel) {
  ViewerOptions o;
  o.model = dissectionBlock();
  o.width = 480;
  o.height = 300;
  o.frames = 16;
  o.show_ui = false;
  o.tool_mode = ToolMode::Cut;
  o.scripted_mouse = [](int frame, double& x, double& y) {
    y = 0.5;
    x = std::clamp(0.05 + 0.09 * (frame - 2), 0.05, 0.95);
    return frame >= 2 && frame <= 12;
  };
  ASSERT_EQ(runViewer(o), 0);
  const FrameReport rep = o.model->advance(1.0 / 60.0);
  EXPECT_EQ(rep.counters.at("cuts_applied"), 1.0);
  EXPECT_EQ(rep.counters.at("sphere_components"), 2.0);
}

// Grasp mode: pressing on the middle of the block and dragging the cursor up by a tenth of the window lifts
// the grasped spheres (max displacement > 3 mm while held; the window's tenth is ~1 cm at the block).
TEST_F(ViewerApp, MouseGraspInGraspModeDragsTheModel) {
  ViewerOptions o;
  o.model = dissectionBlock();
  o.width = 480;
  o.height = 300;
  o.frames = 14;
  o.show_ui = false;
  o.tool_mode = ToolMode::Grasp;
  o.grasp_radius_m = 0.01;
  o.scripted_mouse = [](int frame, double& x, double& y) {
    x = 0.5;
    y = 0.5 - 0.1 * std::clamp((frame - 3) / 6.0, 0.0, 1.0);
    return frame >= 2;
  };
  ASSERT_EQ(runViewer(o), 0);
  const FrameReport rep = o.model->advance(1.0 / 60.0);
  EXPECT_GT(rep.counters.at("grasped"), 0.0);
  EXPECT_GT(rep.max_displacement, 3e-3);  // 0 without the grasp: no gravity, nothing else moves it
}

// The swept surface of a scalpel stroke still in progress (pressed and dragged across the block through the tool
// API, not released, so nothing is cut yet) shows as translucent cyan where it leaves the block; with the layer
// off there is none. Swept pixels: blue clearly above red (the tissue's red is 2.4x its blue, the background's
// blue exceeds its red by 8 levels).
TEST_F(ViewerApp, StrokeInProgressShowsTheSweptSurface) {
  auto sweptFraction = [](const Png& p) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < p.rgb.size(); i += 3) n += (p.rgb[i + 2] > p.rgb[i] + 25 && p.rgb[i + 2] > 80) ? 1 : 0;
    return double(n) / (double(p.w) * p.h);
  };
  for (bool shown : {true, false}) {
    std::unique_ptr<SimulationModel> m = dissectionBlock();
    ToolEvent e;
    e.kind = ToolKind::Cut;
    e.axis = Vec3d(0, 0, -1);
    e.blade_length_m = 0.08;
    for (int k = 0; k <= 3; ++k) {  // across the block on the plane y = 2 mm, from x = -5 cm to +2.5 cm
      e.phase = k == 0 ? ToolPhase::Press : ToolPhase::Drag;
      e.tip = Vec3d(-0.05 + 0.025 * k, 0.002, 0.0);
      ASSERT_TRUE(m->applyTool(e).supported);
    }
    ViewerOptions o;
    o.model = std::move(m);
    o.width = 480;
    o.height = 300;
    o.frames = 3;
    o.show_ui = false;
    o.layers.tool = false;
    o.layers.swept_surface = shown;
    o.screenshot_path = outPath(shown ? "viewer_test_swept.png" : "viewer_test_swept_off.png");
    ASSERT_EQ(runViewer(o), 0);
    const Png p = loadPng(o.screenshot_path);
    ASSERT_EQ(p.w, 480);
    if (shown)
      EXPECT_GT(sweptFraction(p), 0.02);
    else
      EXPECT_LT(sweptFraction(p), 1e-3);
    EXPECT_GT(tissueFraction(p), 0.03);
  }
}

// The metaball organ's spheres layer with the constrained layer on: the spheres are drawn (sphere colour) and
// the fixed ones (the x < -1 cm slab) in the fixed colour, on the left of the picture.
TEST_F(ViewerApp, MetaballSpheresWithFixedOnesMarked) {
  Scene s;
  s.file = "<test:viewer_spheres>";
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.size = Vec3d(0.06, 0.04, 0.03);
  s.geometry.spacing = 0.01;
  s.models.pbd_metaballs = true;
  s.solver.gravity = Vec3d(0, 0, 0);
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(-0.01, 1, 1)}};
  ViewerOptions o;
  o.model = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  o.width = 480;
  o.height = 300;
  o.frames = 2;
  o.show_ui = false;
  o.layers.tool = false;
  o.layers.surface = false;
  o.layers.spheres = true;
  o.layers.constrained = true;
  o.screenshot_path = outPath("viewer_test_spheres.png");
  ASSERT_EQ(runViewer(o), 0);
  const Png p = loadPng(o.screenshot_path);
  ASSERT_EQ(p.w, 480);
  std::size_t sphere = 0, fixed = 0;
  double fixed_x = 0, sphere_x = 0;
  for (int y = 0; y < p.h; ++y)
    for (int x = 0; x < p.w; ++x) {
      const unsigned char* c = &p.rgb[3 * (std::size_t(y) * p.w + x)];
      if (c[0] > 120 && c[1] > 100 && c[2] < 0.45 * c[1] && c[1] > 0.7 * c[0]) {  // fixed: yellow (0.85 G/R, blue ~0.1)
        ++fixed;
        fixed_x += x;
      } else if (c[0] > 100 && c[2] > 0.45 * c[1] && c[2] < 0.8 * c[0] && c[0] > c[1]) {  // tan (0.85, 0.72, 0.50)
        ++sphere;
        sphere_x += x;
      }
    }
  EXPECT_GT(double(sphere) / (480.0 * 300.0), 0.03);
  EXPECT_GT(double(fixed) / (480.0 * 300.0), 0.005);
  ASSERT_GT(fixed, 0u);
  ASSERT_GT(sphere, 0u);
  EXPECT_LT(fixed_x / double(fixed), sphere_x / double(sphere));  // the fixed slab is at the left (-x)
}

// Grasp mode on a block whose bottom row is fixed: dragging the top up stretches it, and the tissue's pull on the
// tool is drawn as the orange arrow from the tip, pointing back down the screen (against the drag).
TEST_F(ViewerApp, GraspDragShowsTheToolForceArrow) {
  Scene s;
  s.file = "<test:viewer_force_block>";
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.size = Vec3d(0.06, 0.04, 0.03);
  s.geometry.spacing = 0.01;
  s.models.pbd_metaballs = true;
  s.solver.gravity = Vec3d(0, 0, 0);
  s.solver.substeps = 2;
  s.pbd.iterations = 5;
  s.fixed = {{Vec3d(-1, -1, -1), Vec3d(1, -0.01, 1)}};
  ViewerOptions o;
  o.model = makeMetaballSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  o.width = 480;
  o.height = 300;
  o.frames = 14;
  o.show_ui = false;
  o.tool_mode = ToolMode::Grasp;
  o.grasp_radius_m = 0.01;
  o.scripted_mouse = [](int frame, double& x, double& y) {
    x = 0.5;
    y = 0.5 - 0.1 * std::clamp((frame - 3) / 6.0, 0.0, 1.0);
    return frame >= 2;
  };
  o.screenshot_path = outPath("viewer_test_force.png");
  ViewerFrameInfo last;
  o.on_frame = [&last](const ViewerFrameInfo& f) { last = f; };
  ASSERT_EQ(runViewer(o), 0);
  EXPECT_GT(last.force_scale_m_per_n, 0.0);
  const Png p = loadPng(o.screenshot_path);
  ASSERT_EQ(p.w, 480);
  double px, py, d;
  ASSERT_TRUE(last.camera.project(last.tool_tip, px, py, d));
  const double tip_row = p.h - py;  // PNG rows run from the top
  std::size_t n = 0;
  double rows = 0;
  for (int y = 0; y < p.h; ++y)
    for (int x = 0; x < p.w; ++x) {
      const unsigned char* c = &p.rgb[3 * (std::size_t(y) * p.w + x)];
      if (c[0] > 200 && c[1] > 80 && c[1] < 180 && c[2] < 60) {
        ++n;
        rows += y;
      }
    }
  ASSERT_GT(n, 30u);
  EXPECT_GT(rows / double(n), tip_row + 5.0);  // below the tip on the screen
}

// The layers together on a dissection block (8 x 5 x 4 cm, 1 cm metaballs, no gravity, the top row fixed) with a
// stroke through its left half (on y = 5 mm from x = -6 cm to 0) still in the tissue: the grasp pulls the
// lower-left part down, opening the cut. Wireframe surface, the fixed spheres' markers (yellow), the stroke's nodal
// points (green; since the merge of s6-cut-mls they live only while the blade is in, so the stroke is not
// released), its swept surface (cyan) and the grasp's force arrows all show at once. INCISION_DOC_LAYERS=PATH also
// writes the picture there, at 960 x 600 (docs/images/viewer_layers.png).
TEST_F(ViewerApp, CutBlockShowsAllLayersTogether) {
  Scene s;
  s.file = "<test:viewer_layers_block>";
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.size = Vec3d(0.08, 0.05, 0.04);
  s.geometry.spacing = 0.01;
  s.models.pbd_metaballs = true;
  s.models.cutting = true;
  s.solver.gravity = Vec3d(0, 0, 0);
  s.solver.substeps = 2;
  s.pbd.iterations = 5;
  s.material.damping_per_s = 6;
  s.fixed = {{Vec3d(-1, 0.015, -1), Vec3d(1, 1, 1)}};
  ToolSpec t;  // the scene's scripted scalpel never runs here (its path starts at t = 100 s)
  t.name = "scalpel";
  t.kind = "scalpel";
  t.length = 0.1;
  t.path = {{100.0, Vec3d(-0.06, 0.005, 0), Vec3d(0, 0, 1)}, {101.0, Vec3d(0.0, 0.005, 0), Vec3d(0, 0, 1)}};
  s.tools = {t};
  std::unique_ptr<SimulationModel> m = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  ToolEvent e;
  e.kind = ToolKind::Cut;
  e.axis = Vec3d(0, 0, -1);
  e.blade_length_m = 0.1;
  for (int k = 0; k <= 3; ++k) {  // press and three drags, not released
    e.phase = k == 0 ? ToolPhase::Press : ToolPhase::Drag;
    e.tip = Vec3d(-0.06 + 0.02 * k, 0.005, 0.0);
    ASSERT_TRUE(m->applyTool(e).supported);
  }
  const char* doc = std::getenv("INCISION_DOC_LAYERS");
  ViewerOptions o;
  o.model = std::move(m);
  o.width = doc ? 960 : 480;
  o.height = doc ? 600 : 300;
  o.frames = 8;
  o.show_ui = false;
  o.layers.wireframe = true;
  o.layers.nodal_points = true;
  o.layers.constrained = true;
  o.tool_mode = ToolMode::Grasp;
  o.grasp_radius_m = 0.01;
  o.scripted_mouse = [](int frame, double& x, double& y) {
    x = 0.4;
    y = 0.6 + 0.08 * std::clamp((frame - 2) / 4.0, 0.0, 1.0);
    return frame >= 1;
  };
  o.screenshot_path = outPath("viewer_test_layers.png");
  ASSERT_EQ(runViewer(o), 0);
  const Png p = loadPng(o.screenshot_path);
  ASSERT_EQ(p.w, o.width);
  std::size_t green = 0, yellow = 0, cyan = 0, orange = 0;
  for (std::size_t i = 0; i < p.rgb.size(); i += 3) {
    const int r = p.rgb[i], g = p.rgb[i + 1], b = p.rgb[i + 2];
    green += (g > 150 && g > r + 50 && g > b + 40) ? 1 : 0;
    yellow += (r > 200 && g > 180 && b < 100) ? 1 : 0;
    cyan += (b > r + 25 && b > 80 && g > r) ? 1 : 0;
    orange += (r > 200 && g > 80 && g < 180 && b < 60) ? 1 : 0;
  }
  const double n = double(p.w) * p.h;
  EXPECT_GT(green / n, 1e-3);
  EXPECT_GT(yellow / n, 1e-3);
  EXPECT_GT(cyan / n, 1e-2);
  EXPECT_GT(orange / n, 1e-4);
  if (doc) std::filesystem::copy_file(o.screenshot_path, doc, std::filesystem::copy_options::overwrite_existing);
}

// The organ (a ball of radius R framed by its bounding box) covers its analytic share of the picture.
TEST_F(ViewerApp, ScriptedCaptureShowsTheOrganAtPlausibleSize) {
  ViewerOptions o;
  o.model = std::make_unique<SaggingBall>();
  o.width = 400;
  o.height = 300;
  o.frames = 10;
  o.show_ui = false;
  o.layers.tool = false;
  o.screenshot_path = outPath("viewer_test_capture.png");
  std::filesystem::remove(o.screenshot_path);
  ASSERT_EQ(runViewer(o), 0);
  const Png p = loadPng(o.screenshot_path);
  ASSERT_EQ(p.w, 400);
  ASSERT_EQ(p.h, 300);
  // OrbitCamera::frameBox: distance = 1.2 r_box / sin(fovy/2), r_box = sqrt(3) R (the ball's bounding box);
  // the ball subtends asin(R / distance); on screen its radius is tan(that) / tan(fovy/2) * (H/2).
  const double fovy = 0.8, dist = 1.2 * std::sqrt(3.0) * 0.1 / std::sin(fovy / 2);
  const double r_px = std::tan(std::asin(0.1 / dist)) / std::tan(fovy / 2) * 150.0;
  const double expected = M_PI * r_px * r_px / (400.0 * 300.0);
  // 8 %: the silhouette's darker rim (grazing light) falls below the colour threshold; level-3 icosphere.
  EXPECT_NEAR(tissueFraction(p), expected, 0.08 * expected);
  // Not a single-colour frame: the headlight makes the centre brighter than the rim.
  const unsigned char* centre = &p.rgb[3 * (std::size_t(150) * 400 + 200)];
  const unsigned char* edge = &p.rgb[3 * (std::size_t(150) * 400 + 200 + int(0.9 * r_px))];
  EXPECT_GT(int(centre[0]), int(edge[0]) + 20);
}

// --camera: the first view looks from the asked yaw and pitch (y up here: the eye's direction from the target is
// (cos p sin y, sin p, cos p cos y)), at the asked distance from the framed centre.
TEST_F(ViewerApp, CameraOptionSetsTheFirstView) {
  ViewerFrameInfo framed, turned;
  for (int k = 0; k < 2; ++k) {
    ViewerOptions o;
    o.model = std::make_unique<SaggingBall>();
    o.width = 200;
    o.height = 150;
    o.frames = 2;
    o.show_ui = false;
    if (k == 1) o.camera = CameraAngles{-60.0, 25.0, 0.9};
    o.on_frame = [&](const ViewerFrameInfo& f) { (k == 0 ? framed : turned) = f; };
    ASSERT_EQ(runViewer(o), 0);
  }
  const double y = -60.0 * M_PI / 180.0, p = 25.0 * M_PI / 180.0;
  const Vec3d dir(std::cos(p) * std::sin(y), std::sin(p), std::cos(p) * std::cos(y));
  EXPECT_NEAR(norm(turned.camera.forward + dir), 0.0, 1e-6);
  // The same target as the default framing: it lies along the default view's axis and 0.9 m along the new one.
  const Vec3d target = turned.camera.eye + turned.camera.forward * 0.9;
  const Vec3d to_target = target - framed.camera.eye;
  EXPECT_NEAR(norm(to_target - framed.camera.forward * dot(to_target, framed.camera.forward)), 0.0, 1e-6);
  EXPECT_GT(dot(to_target, framed.camera.forward), 0.0);
}

// With the panels and the splat layer on, the frame is still mostly background with the organ in it,
// and a recording writes one PNG per frame.
TEST_F(ViewerApp, SplatLayerWithPanelsAndRecording) {
  namespace fs = std::filesystem;
  ViewerOptions o;
  o.factory = [] { return std::unique_ptr<SimulationModel>(std::make_unique<SaggingBall>()); };
  o.width = 960;
  o.height = 600;
  o.frames = 4;
  o.layers.surface = false;
  o.layers.splats = true;
  o.record_dir = outPath("viewer_test_record");
  fs::remove_all(o.record_dir);
  fs::create_directories(o.record_dir);
  o.screenshot_path = outPath("viewer_test_splats.png");
  ASSERT_EQ(runViewer(o), 0);
  int files = 0;
  for (const auto& e : fs::directory_iterator(o.record_dir)) files += e.path().extension() == ".png" ? 1 : 0;
  EXPECT_EQ(files, 4);
  const Png p = loadPng(o.screenshot_path);
  ASSERT_EQ(p.w, 960);
  const double frac = tissueFraction(p);
  EXPECT_GT(frac, 0.02);  // the organ is there (some of it may be under the panel)
  EXPECT_LT(frac, 0.5);
}

// A model without a surface is drawn as particle splats.
TEST_F(ViewerApp, ParticleOnlyModelIsVisible) {
  class Points : public SaggingBall {
   public:
    bool currentSurface(TriangleMesh&) const override { return false; }
  };
  ViewerOptions o;
  o.model = std::make_unique<Points>();
  o.width = 320;
  o.height = 240;
  o.frames = 3;
  o.show_ui = false;
  o.screenshot_path = outPath("viewer_test_points.png");
  ASSERT_EQ(runViewer(o), 0);
  const Png p = loadPng(o.screenshot_path);
  ASSERT_EQ(p.w, 320);
  std::size_t blue = 0;
  for (std::size_t i = 0; i < p.rgb.size(); i += 3) blue += (p.rgb[i + 2] > p.rgb[i] + 30) ? 1 : 0;
  EXPECT_GT(double(blue) / (320.0 * 240.0), 0.03);
}

// The tool under a (scripted) cursor sits on the drawn surface, found from the z-buffer, and the paper's
// z-buffer collision reports it inside once pressed in.
TEST_F(ViewerApp, ToolUnderCursorSitsOnSurfaceAndCollides) {
  for (int mode = 0; mode < 2; ++mode) {
    for (double press : {-0.01, 0.02}) {  // hovering 1 cm above, pressed 2 cm in
      ViewerOptions o;
      o.model = std::make_unique<SaggingBall>();
      o.width = 320;
      o.height = 240;
      o.frames = 2;
      o.show_ui = false;
      o.cursor_x = 0.55;
      o.cursor_y = 0.45;
      o.press_depth_m = press;
      o.collision = mode == 0 ? ToolCollision::DepthBuffer : ToolCollision::SplatZBuffer;
      ViewerFrameInfo last;
      o.on_frame = [&last](const ViewerFrameInfo& f) { last = f; };
      ASSERT_EQ(runViewer(o), 0);
      ASSERT_TRUE(last.tool_on_surface);
      // The picked point is on the ball (radius 0.1 m; the level-3 icosphere's facets lie within 1.2 mm
      // inside the sphere, the sag is 0.2 mm): the surface point, press metres back along the eye ray from
      // the tip, is at |p| = R within 1.5 mm.
      const Vec3d dir = (last.tool_tip - last.camera.eye) * (1.0 / norm(last.tool_tip - last.camera.eye));
      EXPECT_NEAR(norm(last.tool_tip - dir * press), 0.1, 1.5e-3) << mode << " " << press;
      EXPECT_EQ(last.contact.inside, press > 0.0) << mode << " " << press;
      if (press > 0.0) {
        EXPECT_NEAR(last.contact.penetration_m, press, 1.5e-3) << mode;
      }
    }
  }
}

// A real liver surface (../shared/organs, skipped when absent) with a cut slot: the picture shows tissue and
// the cut walls. Set INCISION_DOC_SCREENSHOT=PATH to also write the picture there (docs/images/viewer.png).
TEST_F(ViewerApp, CutLiverShowsTissueAndCutWalls) {
  const std::string path = test::sharedPath("organs/liver-smooth.obj");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "organ mesh absent: " << path;
  TriangleMesh liver = loadMesh(path);
  for (auto& v : liver.vertices) v = v * 0.01;  // the file is in centimetres
  Vec3d lo, hi;
  lo = hi = liver.vertices[0];
  for (const auto& v : liver.vertices)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], v[k]);
      hi[k] = std::max(hi[k], v[k]);
    }
  const Vec3d mid = (lo + hi) * 0.5;
  ViewerOptions o;
  o.model = std::make_unique<testing::CutMeshModel>(liver, mid, Vec3d{0.8, 0.0, 0.6}, 0.004);
  o.width = 1280;
  o.height = 800;
  o.frames = 4;
  o.cursor_x = 0.62;
  o.cursor_y = 0.45;
  o.press_depth_m = 0.004;
  o.collision = ToolCollision::SplatZBuffer;
  o.screenshot_path = outPath("viewer_test_liver.png");
  ViewerFrameInfo last;
  o.on_frame = [&last](const ViewerFrameInfo& f) { last = f; };
  ASSERT_EQ(runViewer(o), 0);
  const Png p = loadPng(o.screenshot_path);
  ASSERT_EQ(p.w, 1280);
  EXPECT_GT(tissueFraction(p), 0.05);
  EXPECT_GT(cutWallFraction(p), 0.002);
  EXPECT_TRUE(last.tool_on_surface);
  if (const char* doc = std::getenv("INCISION_DOC_SCREENSHOT"))
    std::filesystem::copy_file(o.screenshot_path, doc, std::filesystem::copy_options::overwrite_existing);
}

TEST(ViewerAppNoDisplay, SaysSoAndReturnsOne) {
  const char* old = std::getenv("DISPLAY");
  const std::string saved = old ? old : "";
  setenv("DISPLAY", ":4099", 1);  // no server there
  ViewerOptions o;
  o.model = std::make_unique<SaggingBall>();
  o.frames = 1;
  ::testing::internal::CaptureStderr();
  const int rc = runViewer(o);
  const std::string err = ::testing::internal::GetCapturedStderr();
  if (old)
    setenv("DISPLAY", saved.c_str(), 1);
  else
    unsetenv("DISPLAY");
  EXPECT_EQ(rc, 1);
  EXPECT_NE(err.find("incision run"), std::string::npos) << err;
}

TEST(ViewerAppOptions, BadOptionsAreInputErrors) {
  ViewerOptions o;
  EXPECT_THROW(runViewer(o), InputError);  // no model
  o.model = std::make_unique<SaggingBall>();
  o.frames = -1;
  EXPECT_THROW(runViewer(o), InputError);
}

}  // namespace
}  // namespace inc::viewer

// The orbit camera with z up (the scenes' convention): above the target for a positive pitch, the view's up vector
// along +z's projection, the right vector horizontal; a drag keeps the eye's height rule. No GL needed.
TEST(OrbitCameraZUp, EyeAboveTheTargetAndUpAlongZ) {
  inc::viewer::OrbitCamera o;
  o.z_up = true;
  o.target = inc::Vec3d(0.1, 0.2, 0.3);
  o.distance_m = 2.0;
  const inc::Vec3d e = o.eye();
  EXPECT_NEAR(e.z - 0.3, 2.0 * std::sin(o.pitch_rad), 1e-12);
  EXPECT_NEAR(inc::norm(e - o.target), 2.0, 1e-12);
  const inc::viewer::ViewCamera v = o.view(640, 480);
  EXPECT_GT(v.up.z, 0.0);
  EXPECT_NEAR(v.right.z, 0.0, 1e-12);
  o.orbit(0.0, -1000.0);  // pitch clamped below the horizon
  EXPECT_LT(o.eye().z, 0.3);
}

namespace inc::viewer {
namespace {

// A mouse cut stroke across a shipped cutting scene, the path a user draws from the left of the organ towards its
// middle (it once crashed in DissectionSimulation<float>::extendStroke).
TEST_F(ViewerApp, MouseCutStrokeOnShippedCutScenesRunsToTheEnd) {
  for (const char* name : {"steak_cut", "liver_cut"}) {
    SCOPED_TRACE(name);
    SceneViewerSetup s =
        makeSceneViewerSetup(loadSceneFile(test::sourceDir() + "/scenes/" + name + ".json"), BackendKind::Cpu);
    ViewerOptions o;
    o.model = s.factory();
    o.factory = s.factory;
    o.knobs = s.knobs;
    o.frame_dt_s = s.scene->solver.frame_dt;
    o.z_up = true;
    o.width = 640;
    o.height = 420;
    o.frames = 24;
    o.show_ui = false;
    o.tool_mode = ToolMode::Cut;
    o.scripted_mouse = [](int frame, double& x, double& y) {
      x = 0.35 + 0.3 * std::clamp((frame - 4) / 12.0, 0.0, 1.0);
      y = 0.5 - 0.05 * std::clamp((frame - 4) / 12.0, 0.0, 1.0);
      return frame >= 3 && frame <= 18;
    };
    ASSERT_EQ(runViewer(o), 0);
    const FrameReport rep = o.model->advance(1.0 / 60.0);
    EXPECT_TRUE(rep.finite);
    EXPECT_GE(rep.counters.at("cuts_applied"), 1.0);  // the mouse's stroke (and the script's part before it)
  }
}

}  // namespace
}  // namespace inc::viewer
