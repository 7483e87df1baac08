// `incision view`: builds the scene's first model through the model factory and hands it to the viewer.
#include "host/cli/view_command.h"

#include <cstdio>

#include "host/input_error.h"
#if INCISION_HAVE_VIEWER
#include "viewer/viewer_app.h"
#endif

namespace inc::cli {

int runViewCommand(const Scene& scene_in, const ViewCommandOptions& options) {
#if INCISION_HAVE_VIEWER
  Scene scene = scene_in;
  if (options.backend) scene.solver.backend = *options.backend;
  const BackendChoice choice = resolveBackend(scene.solver.backend);
  if (!choice.note.empty()) std::fprintf(stderr, "%s\n", choice.note.c_str());
  // The factory also serves the viewer's reset button: a fresh model from the same scene.
  auto build = [scene, kind = choice.kind]() -> std::unique_ptr<SimulationModel> {
    auto models = createSceneModels(scene, kind);
    if (models.empty()) throw InputError(scene.file, "models", "the scene switches on no model to show");
    return std::move(models.front());
  };
  viewer::ViewerOptions vo;
  vo.model = build();
  vo.factory = build;
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
