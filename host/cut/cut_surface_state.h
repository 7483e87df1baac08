// The organ's rest surface through a sequence of cuts: split per cut, wall flags, and skinning that crosses no cut.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/assembly/skin_binding.h"
#include "host/cut/cut_surface_split.h"

namespace inc {

struct CutSurfaceState {
  TriangleMesh mesh;               // rest configuration, after every cut so far
  std::vector<std::uint8_t> wall;  // per triangle: 1 = cut wall (SimulationModel::cutWallTriangles)
  std::vector<Vec3d> probe;        // per vertex: where its skin binding looks from (SurfaceSplit::binding_probe)
  int splits = 0;                  // cuts that crossed the surface
  bool checked = false;  // mesh is a split's output, checked closed and manifold (SurfaceSplitOptions::input_checked)
};

// The uncut surface.
CutSurfaceState cutSurfaceState(const TriangleMesh& rest);

// Splits the current surface along `sweep` (rest configuration; any shape, a partial cut leaves a slit). The
// state changes only when the blade crossed the surface (split == true). Wall flags and probes of the triangles
// and vertices that existed before carry over (a wall crossed by a later cut stays a wall). A split that stays
// inconsistent (CutSplitFailed) leaves the state unchanged and says why in `failure`; bad input still throws.
SurfaceSplit applySurfaceCut(CutSurfaceState& state, const SweptSurface& sweep,
                             const SurfaceSplitOptions& options = {});

// Skin binding (bindSkin, k nearest by signed sphere distance) restricted, per vertex, to the spheres whose
// centre the vertex's probe sees without crossing any of `cuts` (the visibility criterion of section 5.2 applied
// to skin weights): each side of a cut follows only its own spheres, and the flesh beyond a partial cut's front
// still binds both. A vertex that sees no sphere binds unfiltered.
SkinBinding bindSkinAcrossCuts(const CutSurfaceState& state, const MetaballModel& spheres,
                               const std::vector<SweptSurface>& cuts, int k = 4, const std::string& file = "");

}  // namespace inc
