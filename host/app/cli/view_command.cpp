// `incision view`: builds the scene's first model through the model factory and hands it to the viewer.
#include "host/app/cli/view_command.h"
#include "host/scene/scene_compile.h"

#include <cmath>
#include <cstdio>

#include "model/input_error.h"
#if INCISION_HAVE_VIEWER
#include "host/haptics/haptic_scene_model.h"
#include "host/haptics/pointer_device.h"
#include "viewer/scene_knobs.h"
#include "viewer/viewer_app.h"
#endif

namespace inc::cli {

int runViewCommand(const Scene& scene_in, const ViewCommandOptions& options) {
#if INCISION_HAVE_VIEWER
  // The Material / Solver panels edit a copy of the scene; the factory rebuilds the model from it (also
  // on reset), so the knobs' changes reach the simulation (viewer/scene_knobs.h).
  viewer::SceneViewerSetup setup = viewer::makeSceneViewerSetup(scene_in, options.backend);
  if (!setup.backend_note.empty()) std::fprintf(stderr, "%s\n", setup.backend_note.c_str());
  const Scene& scene = *setup.scene;
  viewer::ViewerOptions vo;
  // models.haptics: the mouse drives a PointerDevice in place of the first device; each model the factory builds
  // runs that hand's haptic loop on it (the first device's own driver is for `incision run`; any further device
  // runs its own driver here too). The pointer's triple buffers have one reader and one writer,
  // so a rebuild stops the previous model's loop first (and restarts it when the rebuild fails).
  std::shared_ptr<PointerDevice> pointer;
  if (scene.models.haptics) {
    pointer = std::make_shared<PointerDevice>(scene.haptics.devices.at(0).max_force_n);
    auto last = std::make_shared<HapticSceneModel*>(nullptr);
    setup.factory = [base = setup.factory, sc = setup.scene, pointer, last]() -> std::unique_ptr<SimulationModel> {
      if (*last) (*last)->haptics().stop();
      try {
        SceneHapticsOptions ho;
        ho.device = pointer;
        ho.record_s = 10.0;  // the viewer plots the loop through the model counters, not the records
        // Interactive: the cut may lag the hand by five frames at most (a pause, frames slower than real time).
        ho.max_cut_lag_s = 5.0 * sc->solver.frame_dt;
        auto m = std::make_unique<HapticSceneModel>(base(), compileScene(*sc), ho);
        *last = m.get();
        return m;
      } catch (...) {
        if (*last) (*last)->haptics().start();
        throw;
      }
    };
  }
  vo.model = setup.factory();
  if (pointer) {
    const TissuePlane plane = static_cast<HapticSceneModel&>(*vo.model).haptics().plane();
    vo.haptic_pointer = pointer;
    vo.haptic_plane_point_m = plane.point_m;
    vo.haptic_plane_normal = plane.normal;
  }
  vo.factory = setup.factory;
  vo.knobs = setup.knobs;
  vo.title = "Incision: " + scene.name;
  vo.frame_dt_s = scene.solver.frame_dt;
  // The scenes' convention is z up (gravity along -z); a scene whose gravity points mainly along y keeps y up.
  const Vec3d g = scene.solver.gravity;
  vo.z_up = !(std::fabs(g.y) > std::fabs(g.x) && std::fabs(g.y) > std::fabs(g.z));
  vo.frames = options.frames;
  vo.camera = options.camera;
  vo.screenshot_path = options.screenshot;
  vo.layers.splats = options.splats;
  vo.layers.surface = !options.splats;
  return viewer::runViewer(vo);
#else
  (void)scene_in;
  (void)options;
  std::fprintf(stderr,
               "incision: this build has no viewer (GLFW, Dear ImGui or OpenGL were not found); "
               "use `incision run` for headless runs\n");
  return 1;
#endif
}

}  // namespace inc::cli
