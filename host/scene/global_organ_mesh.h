// The scene keys of the BEM global model (haptics.global_model and its mesh and cache) that the key table cannot
// read alone: paths resolved, the mesh loaded and checked (host/compiled/bem_organ_mesh.h), the cache named.
#pragma once

#include <string>
#include <vector>

#include "host/compiled/bem_organ_mesh.h"
#include "host/scene/scene.h"
#include "host/scene/scene_json.h"

namespace inc {

// After the key table has read h.global_model and h.global_mesh_scale: refuses the global_* keys unless
// global_model is "bem"; with "bem", global_mesh (resolved against base_dir, loaded and checked) and global_cache
// (default: the scene file's name with .bemcache in its folder; a scene without a file caches next to the mesh).
// Throws InputError(file, "haptics.<key>", reason), also when no element of the organ lies in a `fixed` region
// (the BEM system would be singular).
void readGlobalModelKeys(const scene_json::ObjectReader& haptics, const std::string& base_dir,
                         const std::vector<FixedRegion>& fixed, HapticsSpec& h);

}  // namespace inc
