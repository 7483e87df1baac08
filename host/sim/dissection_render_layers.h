// The dissection model's cut layer for the viewer: swept cut surfaces, moved from the rest configuration to the
// current one by the spheres.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/cut/cut_swept_surface.h"
#include "host/sim/simulation_model.h"

namespace inc {

// Swept surfaces live in the rest configuration (the cut pipeline works there). They are shown where the tissue
// is now by translation skinning, as the organ's surface: v = v0 + sum_j w_j (x_j - c_j) over the k = 4 spheres
// nearest in signed distance (host/assembly/skin_binding.h). A swept surface binds to the spheres on both sides (it
// lies between the walls). The binding is rebuilt only when the surfaces or the spheres change. (The nodal points need
// no binding: while a stroke is in the tissue they are simulated, and the model reports where they are.)
class CutLayerBinding {
 public:
  // `swept`: every swept surface to show (null or empty ones are skipped).
  void update(const std::vector<const SweptSurface*>& swept, const MetaballModel& spheres);
  // Fills out.swept_surface from the spheres' current centres (one per sphere).
  void apply(const std::vector<Vec3d>& sphere_positions, RenderLayers& out) const;

 private:
  struct Bound {  // translation skinning slots v * k + j
    int k = 0;
    std::vector<Vec3d> rest;
    std::vector<std::int32_t> sphere;
    std::vector<double> weight;
  };
  static void bind(Bound& into, const std::vector<Vec3d>& points, const MetaballModel& spheres);
  static void move(const Bound& b, const std::vector<Vec3d>& rest_centres, const std::vector<Vec3d>& now,
                   std::vector<Vec3d>& out);

  double key_[3] = {-1, -1, -1};
  std::vector<Vec3d> rest_centres_;
  std::vector<std::array<int, 3>> swept_triangles_;
  Bound swept_;
};

}  // namespace inc
