// Scene keys of the haptic loops (the `haptics` section): reading and validation (the key table writes them).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "host/scene/scene.h"
#include "host/scene/scene_json.h"

namespace inc {

// Reads the optional `haptics` section of `top` (docs/scene-format.md): one device (its keys in `haptics`) or
// the list `haptics.devices` (1 to 4). Relative trajectory and mesh paths are resolved against base_dir (the scene
// file's folder) and the files are loaded once to check them. Throws InputError(file, key path, reason) for an
// unknown key, a value out of range, a device this build cannot drive, a trajectory file that cannot be read
// (its own file and line are in the reason), devices that clash (name, UDP port, a second OpenHaptics device or
// scalpel), or a global model whose organ mesh cannot be used (open, too large, held nowhere by `fixed`).
HapticsSpec readHapticsSpec(const scene_json::ObjectReader& top, const std::string& base_dir, const ModelsSpec& models,
                            const std::vector<FixedRegion>& fixed);

// Whether this build has the OpenHaptics driver (CMake found the SDK: INCISION_WITH_OPENHAPTICS).
bool openHapticsBuilt();

}  // namespace inc
