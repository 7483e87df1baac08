// The scene description: what a JSON scene file says, validated, in SI units (see docs/scene-format.md). Read by
// the loader, the writer and the application only: compileScene (host/scene/scene_compile.h) turns it into the
// CompiledScene every layer below the application is built from.
#pragma once

#include <string>
#include <vector>

#include "host/compiled/compiled_scene.h"

namespace inc {

// What `incision run` writes (`output`): an application setting, not part of the compiled scene.
struct OutputSpec {
  int every_frames = 0;  // 0: final state only; N: also every N frames
  bool particles_ply = true;
  bool mesh_obj = true;
  bool vtk = false;  // legacy VTK point/mesh files for ParaView
  bool metrics_csv = true;
};

// The scene file's model inputs (the CompiledScene it derives from, which compileScene hands to the layers below the
// application) and what only the application reads: the name, description, run length and output settings.
struct Scene : CompiledScene {
  std::string name;
  std::string description;
  double duration = 1.0;  // s, default run length when neither --steps nor --seconds is given
  OutputSpec output;
  // Settings the loader chose because the file left them out and a fixed default would not fit the body (e.g.
  // geometry.spacing_m of a mesh, from its volume and thickness): "key = value (why)", printed by validate and run.
  std::vector<std::string> chosen_settings;
  // What a valid scene will do that its author may not expect (e.g. nothing holds the body, so it falls), one line
  // each, printed as "note: ..." by validate and run.
  std::vector<std::string> notes;
};

}  // namespace inc