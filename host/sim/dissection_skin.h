// The dissection's skin: the translation-skinning slots that carry the organ's surface on its spheres.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "host/assembly/skin_binding.h"
#include "physics/vec3.h"

namespace inc::dissection {

struct Skin {  // translation skinning slots v * k + j (sphere index into the bound model, weight)
  int k = 0;
  std::vector<Vec3d> rest_vertices;
  std::vector<std::int32_t> sphere;
  std::vector<double> weight;
};

// The slots of a binding (the rest of it, the normals' incidence, is not needed to move the vertices).
inline Skin skinSlots(SkinBinding b) {
  return Skin{b.k, std::move(b.rest_vertices), std::move(b.sphere), std::move(b.weight)};
}

}  // namespace inc::dissection
