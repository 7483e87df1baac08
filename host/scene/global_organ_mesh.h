// The scene keys of the BEM global model (haptics.global_model and its mesh and cache): reading and writing. The
// mesh itself is loaded and checked by host/compiled/bem_organ_mesh.h.
#pragma once

#include <string>
#include <vector>

#include "host/compiled/bem_organ_mesh.h"
#include "host/scene/scene.h"
#include "host/scene/scene_json.h"

namespace inc {

// haptics.global_model and, with "bem", global_mesh (resolved against base_dir, loaded and checked),
// global_mesh_scale and global_cache (default: the scene file's name with .bemcache in its folder; a scene without
// a file caches next to the mesh). Throws InputError(file, "haptics.<key>", reason), also when no element of the
// organ lies in a `fixed` region (the BEM system would be singular).
void readGlobalModelKeys(const scene_json::ObjectReader& haptics, const std::string& base_dir,
                         const std::vector<FixedRegion>& fixed, HapticsSpec& h);
// The same keys for sceneToJson (global_mesh, global_cache written absolute).
void writeGlobalModelKeys(const HapticsSpec& h, nlohmann::ordered_json& haptics);

}  // namespace inc
