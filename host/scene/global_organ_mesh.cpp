// The scene keys of the BEM global model (haptics.global_model, global_mesh, ...): reading and writing.
#include "host/scene/global_organ_mesh.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "model/input_error.h"

namespace inc {

void readGlobalModelKeys(const scene_json::ObjectReader& r, const std::string& base_dir,
                         const std::vector<FixedRegion>& fixed, HapticsSpec& h) {
  if (h.global_model != "bem") {
    for (const char* k : {"global_mesh", "global_mesh_scale", "global_cache"})
      if (r.has(k)) r.fail(k, "is used only with global_model \"bem\"");
    return;
  }
  if (!r.has("global_mesh"))
    r.fail("global_mesh", "is required with global_model \"bem\" (the organ's closed surface mesh)");
  const std::string rel = r.string("global_mesh", "");
  if (rel.empty()) r.fail("global_mesh", "must name a mesh file");
  h.global_mesh = scene_json::resolvePath(rel, base_dir);
  TriangleMesh mesh;
  try {
    mesh = loadGlobalOrganMesh(h.global_mesh, h.global_mesh_scale);
  } catch (const InputError& e) {
    r.fail("global_mesh", e.what());
  }
  const std::vector<BemBc> bc = organSupports(mesh, fixed);
  if (std::find(bc.begin(), bc.end(), BemBc::kDisplacement) == bc.end())
    r.fail("global_mesh", h.global_mesh +
                              ": no element centroid lies in a fixed region: the BEM global model needs the "
                              "organ held somewhere (a `fixed` box around part of its surface)");
  if (r.has("global_cache")) {
    const std::string c = r.string("global_cache", "");
    if (c.empty()) r.fail("global_cache", "must name a file (the precompute is always cached)");
    h.global_cache = scene_json::resolvePath(c, base_dir);
  } else if (!r.file().empty() && r.file()[0] != '<') {
    h.global_cache = scene_json::resolvePath(std::filesystem::path(r.file()).stem().string() + ".bemcache", base_dir);
  } else {
    h.global_cache = h.global_mesh + ".bemcache";
  }
}

}  // namespace inc
