// `incision view`: builds the scene's first model through the model factory and hands it to the viewer.
#include "host/cli/view_command.h"

#include <cstdio>

#include "host/input_error.h"
#if INCISION_HAVE_VIEWER
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
  vo.model = setup.factory();
  vo.factory = setup.factory;
  vo.knobs = setup.knobs;
  vo.title = "Incision: " + scene.name;
  vo.frame_dt_s = scene.solver.frame_dt;
  vo.frames = options.frames;
  vo.screenshot_path = options.screenshot;
  vo.layers.splats = options.splats;
  vo.layers.surface = !options.splats;
  return viewer::runViewer(vo);
#else
  (void)scene_in;
  (void)options;
  std::fprintf(stderr, "incision: this build has no viewer (GLFW, Dear ImGui or OpenGL were not found); "
                       "use `incision run` for headless runs\n");
  return 1;
#endif
}

}  // namespace inc::cli
