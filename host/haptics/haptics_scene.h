// Scene keys of the haptic loop (the `haptics` section): reading, validation and writing.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "host/scene.h"
#include "host/scene_json.h"

namespace inc {

// Reads the optional `haptics` section of `top` (docs/scene-format.md). Relative trajectory paths are resolved
// against base_dir (the scene file's folder) and the file is loaded once to check it. Throws
// InputError(file, "haptics.<key>", reason) for an unknown key, a value out of range, a device this build
// cannot drive, or a trajectory file that cannot be read (its own file and line are in the reason).
HapticsSpec readHapticsSpec(const scene_json::ObjectReader& top, const std::string& base_dir);

// The same keys for sceneToJson (reads back to the same values).
nlohmann::ordered_json hapticsSpecJson(const HapticsSpec& h);

// Whether this build has the OpenHaptics driver (CMake found the SDK: INCISION_WITH_OPENHAPTICS).
bool openHapticsBuilt();

}  // namespace inc
