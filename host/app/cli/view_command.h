// `incision view`: the scene in the GLFW + ImGui viewer (declared here, built only with the viewer).
#pragma once

#include <optional>
#include <string>

#include "host/app/camera_option.h"
#include "host/app/runner.h"
#include "host/scene/scene.h"

namespace inc::cli {

struct ViewCommandOptions {
  std::optional<BackendKind> backend;
  int frames = 0;                      // > 0: scripted run of N frames, then exit (with `screenshot`)
  std::string screenshot;              // PNG written after the last scripted frame
  bool splats = false;                 // start with point splats instead of the shaded surface
  std::optional<CameraAngles> camera;  // --camera YAW,PITCH[,DISTANCE]; unset: the default framing
};

// Returns the process exit code: 0, 1 when no display / no OpenGL 3.3 or no viewer in this build.
int runViewCommand(const Scene& scene, const ViewCommandOptions& options);

}  // namespace inc::cli
