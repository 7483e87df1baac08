// The scene format's keys, each described once, in one row: path, type, unit, range, default (docs/scene-format.md's
// tables) and the binding to its C++ field, which reads, checks and writes it.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace inc {

struct SceneField;  // host/scene/scene_fields.h

// One key of the scene format. Its row drives everything that names the key: the loader's unknown-key check and
// did-you-mean suggestions take their key lists from the table; the section readers of scene_loader.cpp read
// every bound key through `field` (its type and simple range, "is required"), then check what involves several
// keys in code; sceneToJson writes the whole scene by walking the table; tests/scene/test_scene_keys.cpp checks
// that the table and docs/scene-format.md's key tables name the same keys, that every row has a binding and
// that every bound key is written and read back. A new key is one row here (and its field in scene.h, its row in
// the docs).
struct SceneKey {
  const char* path;      // "material.youngs_modulus_pa"; "[]" stands for any element of an array: "tools[].path[].t_s"
  const char* type;      // number, integer, boolean, string, vec3, object, array ... (as the docs say)
  const char* unit;      // "-" when it has none
  const char* range;     // the accepted values, as the docs state them
  const char* fallback;  // the default when the key is absent ("required" when it must be given)
  std::shared_ptr<const SceneField> field;  // its field in the struct of its parent object (scene_fields.h)
  const char* kinds = "";  // space-separated values of the object's `kind` that use the key; "": every kind
};

// Every key, parents before their children, each object's keys in the order they are read and written (the order an
// unknown-key error names them in).
const std::vector<SceneKey>& sceneKeys();

// The keys directly under `parent` ("" = the top level, "material", "tools[].path[]"), in table order. With `kind`,
// only those whose `kinds` is empty or names it (a plane collider's keys: sceneKeysUnder("colliders[]", "plane")).
std::vector<std::string> sceneKeysUnder(const std::string& parent, const std::string& kind = "");

// The keys under `parent` that only some kinds use (geometry's center_m, size_m, ...), and those `kind` uses.
std::vector<std::string> kindSpecificKeysUnder(const std::string& parent);
std::vector<std::string> kindSpecificKeysUnder(const std::string& parent, const std::string& kind);

}  // namespace inc
