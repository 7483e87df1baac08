// The scene format's keys, each described once: path, type, unit, range and default (docs/scene-format.md's tables).
#pragma once

#include <string>
#include <vector>

namespace inc {

// One key of the scene format. The loader's unknown-key check and did-you-mean suggestions take their key lists
// from here, and tests/scene/test_scene_keys.cpp checks that this table and docs/scene-format.md's key tables name
// the same keys, so a new key is added here, read in scene_loader.cpp, written in sceneToJson and documented.
struct SceneKey {
  const char* path;      // "material.youngs_modulus_pa"; "[]" stands for any element of an array: "tools[].path[].t_s"
  const char* type;      // number, integer, boolean, string, vec3, object, array ... (as the docs say)
  const char* unit;      // "-" when it has none
  const char* range;     // the accepted values, as the docs state them
  const char* fallback;  // the default when the key is absent ("required" when it must be given)
  const char* kinds = "";  // space-separated values of the object's `kind` that use the key; "": every kind
};

// Every key, parents before their children, each object's keys in the order its reader lists them (the order an
// unknown-key error names them in).
const std::vector<SceneKey>& sceneKeys();

// The keys directly under `parent` ("" = the top level, "material", "tools[].path[]"), in table order. With `kind`,
// only those whose `kinds` is empty or names it (a plane collider's keys: sceneKeysUnder("colliders[]", "plane")).
std::vector<std::string> sceneKeysUnder(const std::string& parent, const std::string& kind = "");

// The keys under `parent` that only some kinds use (geometry's center_m, size_m, ...), and those `kind` uses.
std::vector<std::string> kindSpecificKeysUnder(const std::string& parent);
std::vector<std::string> kindSpecificKeysUnder(const std::string& parent, const std::string& kind);

}  // namespace inc
