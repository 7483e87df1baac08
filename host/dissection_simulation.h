// The dissection model: PBD metaball organ cut by a scripted scalpel (nodal points, re-packing, cut surface).
#pragma once

#include <memory>

#include "host/backend.h"
#include "host/mesh.h"
#include "host/scene.h"
#include "host/scene_surface.h"
#include "host/simulation_model.h"

namespace inc {

// Needs models.cutting and models.pbd_metaballs and one tool of kind "scalpel" (the first is used; with
// models.haptics the scripted scalpel is optional: a haptic device drives the blade through applyTool): the blade
// is the segment of tool.length centred on the path position along the path direction. While the path runs
// the blade sweeps a surface (one strip per frame, in the rest configuration); when the path ends the cut is
// applied: cut spheres -> nodal points (visibility-filtered) -> re-packed spheres, PBD model rebuilt without
// links across the cut, surface split along the swept surface with both cut walls, skin re-bound.
// currentSurface() is the (cut) surface moved by the spheres (translation skinning). Counters: spheres,
// cut_spheres_pending, cuts_applied, nodal_points_last_cut, spheres_added_last_cut, surface_split,
// cut_apply_ms, sweep_ms, surface_components, sphere_components (of the link graph), links, grasped.
// The interactive tool (SimulationModel::applyTool): grasp & drag, and mouse scalpel strokes that are cut by
// the same pipeline when they end (any number of cuts, each splitting the surface; cutWallTriangles() flags
// the wall triangles).
std::unique_ptr<SimulationModel> makeDissectionSimulation(const Scene& scene, BackendKind backend, Precision precision);

}  // namespace inc
