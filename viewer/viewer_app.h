// The interactive viewer: a GLFW window with ImGui panels showing a SimulationModel as it runs.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "host/app/camera_option.h"
#include "host/haptics/pointer_device.h"
#include "host/sim/simulation_model.h"
#include "viewer/sim_runner.h"
#include "viewer/zbuffer_collision.h"

namespace inc::viewer {

struct ViewLayers {
  bool surface = true;     // the model's surface mesh, Phong shaded (inner side in the cut-wall colour)
  bool splats = false;     // the surface drawn as Gaussian point splats instead (paper, section 3)
  bool particles = false;  // every particle (nodal points, metaball centres) as view-facing splats
  bool wireframe = false;
  bool tool = true;  // the tool tip under the mouse
  // The model's own layers (SimulationModel::renderLayers; viewer/model_layers.h):
  bool spheres = false;       // metaball spheres at their radius (ray-cast impostors)
  bool nodal_points = false;  // MLS nodal points (green splats)
  bool constrained = false;   // fixed particles (yellow) and particles a tool holds (magenta)
  bool swept_surface = true;  // the scalpel's swept cut surface (translucent cyan)
  bool forces = true;         // tool reaction (orange) and per-particle external forces (white), on top
  bool colliders = true;      // the scene's static colliders (translucent grey)
};

// What the left mouse button does over the model.
enum class ToolMode {
  Camera,  // orbit (the default)
  Grasp,   // press grabs what is under the tip, drag moves it, release lets go (SimulationModel::applyTool)
  Cut,     // press starts a scalpel stroke, drag draws it, release cuts
};

enum class ToolCollision {
  DepthBuffer,   // the tip sits on the drawn surface under the cursor (z-buffer read-back)
  SplatZBuffer,  // the paper's z-buffer collision against the particle splats along the eye ray
};

// What a frame showed, for scripted runs and tests (ViewerOptions::on_frame).
struct ViewerFrameInfo {
  int index = 0;                 // displayed frames so far, from 0
  std::uint64_t sim_frame = 0;   // the snapshot's simulation frame
  bool tool_on_surface = false;  // the cursor is over drawn geometry
  Vec3d tool_tip;                // m, world
  ZContact contact;              // of the active collision mode
  ViewCamera camera;
  double force_scale_m_per_n = 0.0;  // of the force arrows drawn (0: none)
};

struct ViewerOptions {
  // The model to show: `model`, or built by `factory` (which also rebuilds it on reset). When both are set
  // the model is shown first and the factory serves resets. The viewer borrows `model` for the call.
  std::unique_ptr<SimulationModel> model;
  ModelFactory factory;
  std::vector<ViewerKnob> knobs;  // live parameters (Young's modulus, iterations, substeps, ...)
  std::string title = "Incision";
  int width = 1280;  // window, screen coordinates
  int height = 800;
  bool vsync = true;
  double frame_dt_s = 1.0 / 60.0;  // simulated seconds per frame (at slow-motion scale 1)
  bool threaded = true;            // simulation on its own thread; scripted runs (frames > 0) always pump
  int frames = 0;                  // > 0: render this many frames, then exit (scripted capture, tests)
  std::string screenshot_path;     // written after the last scripted frame; the P key writes numbered ones
  std::string record_dir;          // non-empty: every frame written as record_dir/frame_00000.png
  bool show_ui = true;
  bool start_paused = false;
  double particle_radius_m = 0.0;      // 0: from the particles' mean spacing
  bool z_up = false;                   // the camera keeps world +z up (scenes with gravity along -z); false: +y
  std::optional<CameraAngles> camera;  // the first view's yaw, pitch (and distance); unset: the default framing
  ViewLayers layers;
  double force_scale_m_per_n = 0.0;  // force arrows, metres per newton; 0: the longest is a quarter of the scene radius
  ToolCollision collision = ToolCollision::DepthBuffer;
  ToolMode tool_mode = ToolMode::Camera;
  double grasp_radius_m = 0.0;  // 0: 8 % of the scene's radius
  double blade_length_m = 0.0;  // 0: the scene's diameter (the blade, centred on the tip, cuts through)
  // Scripted cursor in window fractions (0, 0 top-left .. 1, 1 bottom-right); negative: the real mouse.
  double cursor_x = -1.0, cursor_y = -1.0;
  double press_depth_m = 0.0;  // m, the tool tip below the surface under the cursor (negative: above)
  // Scripted mouse for tests and captures: called every frame with the frame index; returns whether the left
  // button is down and may set the cursor (window fractions; negative: unchanged). Overrides the real button
  // for the grasp / cut tool.
  std::function<bool(int frame, double& cursor_x, double& cursor_y)> scripted_mouse;
  // A haptics scene (models.haptics): the mouse drives this device of the model's haptic loop. Every frame the
  // tip under the cursor is sent as its pose (left button = button bit 0), shifted along the tissue plane's
  // normal so that the depth below the plane is the tip's press depth below the drawn surface (ctrl + wheel);
  // while a grasp / cut drag is held the tip moves in its view plane. In cut mode the haptic cutting tool's
  // decisions (eqs. 15-16) cut instead of the mouse stroke. The loop's force shows as the tool arrow.
  std::shared_ptr<PointerDevice> haptic_pointer;
  Vec3d haptic_plane_point_m;  // the tissue plane of the haptic contact model (SceneHaptics::plane)
  Vec3d haptic_plane_normal{0, 0, 1};
  std::function<void(const ViewerFrameInfo&)> on_frame;  // called after each frame is drawn
  bool verbose = false;                                  // print the GL version and progress to stdout
};

// Runs until the window closes (or `frames` frames). Returns 0 on success, 1 when no display or no
// OpenGL 3.3 context is available (a message on stderr suggests `incision run`) or rendering failed.
// Throws InputError for invalid options.
int runViewer(const ViewerOptions& options);

}  // namespace inc::viewer
