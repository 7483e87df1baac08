// Building an MLS model from its inputs: validation, rest neighbourhoods, densities, volumes, moment matrices.
#pragma once

#include <vector>

#include "model/mls_model.h"
#include "model/neighbor_lists.h"
#include "physics/vec3.h"

namespace inc {

// Throws InputError(source, key, reason) for any value outside its documented range.
void validateMlsBuildInput(const MlsBuildInput& in);

// Coefficients (Lame, volume penalty) in double from the material.
MlsCoefficients<double> mlsCoefficients(const MlsMaterial& m);

// The rest neighbourhoods of a solid (computed once; rebuilt on topology changes) with the shared CPU grid
// search (inc::cpu::GridNeighborSearch). One radius for all particles, so the lists are symmetric.
template <typename T>
NeighborLists buildMlsRestNeighbors(const std::vector<Vec3<T>>& rest, T radius);

// Validates, finds rest neighbourhoods, densities, volumes, A_i^{-1} (computed in double from the
// precision-T rest positions, then rounded) and the degeneracy counts.
template <typename T>
MlsModel<T> buildMlsModel(const MlsBuildInput& in);

}  // namespace inc
