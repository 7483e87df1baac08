// The metaball organ: overlapping spheres (centres, radii, masses) and the links between them.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "physics/vec3.h"

namespace inc {

// Rest configuration of a packed organ; changes only on topology events (cut, re-packing).
struct MetaballModel {
  std::vector<Vec3d> rest_centers;                 // m
  std::vector<double> rest_radii;                  // m
  std::vector<double> masses;                      // kg, density * sphere volume share
  std::vector<std::array<std::int32_t, 2>> links;  // overlapping sphere pairs (i < j), unique
  std::vector<double> link_rest_lengths;           // m, |c_i - c_j| at rest
  std::size_t size() const { return rest_centers.size(); }
};

// Connected components of the sphere graph (spheres as nodes, links as edges).
int sphereGraphComponents(const MetaballModel& model);

}  // namespace inc
