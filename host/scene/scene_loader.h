// Reads, validates and writes JSON scene files (schema and error forms in docs/scene-format.md).
#pragma once

#include <string>

#include "host/scene/scene.h"

namespace inc {

// Reads and validates a scene file. Throws InputError(file, key path, reason) for a missing or unreadable file,
// invalid JSON (line and column), unknown keys (did-you-mean), wrong types, non-finite numbers, out-of-range
// values, inconsistent model choices and, for geometry.kind "mesh", a mesh that does not load or is not closed.
Scene loadSceneFile(const std::string& path);

// The same from text already in memory. `file_label` names the input in messages and becomes Scene::file;
// relative mesh paths are resolved against `base_dir` ("" = the current directory).
Scene parseScene(const std::string& json_text, const std::string& file_label, const std::string& base_dir);

// Every key of the scene as JSON (2-space indented); parseScene(sceneToJson(s), ...) gives back `s`.
std::string sceneToJson(const Scene& scene);

}  // namespace inc
