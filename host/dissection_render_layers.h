// The dissection model's cut layers for the viewer: swept cut surfaces and the last cut's nodal points, moved from
// the rest configuration to the current one by the spheres.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "host/cut_nodal_points.h"
#include "host/cut_swept_surface.h"
#include "host/metaball_model.h"
#include "host/simulation_model.h"

namespace inc {

// Swept surfaces and nodal points live in the rest configuration (the cut pipeline works there). They are
// shown where the tissue is now by translation skinning, as the organ's surface: v = v0 + sum_j w_j (x_j - c_j)
// over the k = 4 spheres nearest in signed distance (host/skin_binding.h). A swept surface binds to the
// spheres on both sides (it lies between the walls); a nodal point only to the spheres on its own side of the
// cut it came from, so the two sides' points part with their walls. The bindings are rebuilt only when the
// surfaces, the spheres or the nodal points change.
class CutLayerBinding {
 public:
  // `swept`: every swept surface to show (null or empty ones are skipped); `nodal_cut`: the cut the nodal
  // points came from (null: bind them to all spheres).
  void update(const std::vector<const SweptSurface*>& swept, const NodalPoints& nodal, const SweptSurface* nodal_cut,
              const MetaballModel& spheres);
  // Fills out.swept_surface and out.nodal_points from the spheres' current centres (one per sphere).
  void apply(const std::vector<Vec3d>& sphere_positions, RenderLayers& out) const;

 private:
  struct Bound {  // translation skinning slots v * k + j
    int k = 0;
    std::vector<Vec3d> rest;
    std::vector<std::int32_t> sphere;
    std::vector<double> weight;
  };
  static void append(Bound& into, const std::vector<Vec3d>& points, const MetaballModel& spheres,
                     const std::vector<std::int32_t>* subset);
  static void move(const Bound& b, const std::vector<Vec3d>& rest_centres, const std::vector<Vec3d>& now,
                   std::vector<Vec3d>& out);

  double key_[4] = {-1, -1, -1, -1};
  std::vector<Vec3d> rest_centres_;
  std::vector<std::array<int, 3>> swept_triangles_;
  Bound swept_, nodal_;
};

}  // namespace inc
