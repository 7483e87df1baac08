// The dissection model: PBD metaball organ cut by scalpel strokes (nodal points, re-packing, cut surface).
#pragma once

#include <memory>

#include "host/assembly/scene_surface.h"
#include "host/compiled/compiled_scene.h"
#include "host/io/mesh.h"
#include "host/sim/simulation_model.h"
#include "model/backend.h"

namespace inc {

// Needs models.cutting and models.pbd_metaballs and at least one tool of kind "scalpel" (with models.haptics the
// scripted scalpels are optional: a haptic device drives the blade through applyTool). Every scalpel is one
// stroke (from its first keyframe's time to its last; strokes may not overlap in time): the blade is the segment
// of tool.length centred on the path position along the path direction, and sweeps a surface in the rest
// configuration, one strip per frame. While it is in the tissue (sections 5.1-5.3):
//  - spheres the new strip enters become MLS nodal points (m / n each); their PBD-linked neighbours become
//    interface spheres, sampled likewise (their points are the "overlapping points"), kept in the PBD model as
//    kinematic spheres; supports crossing the swept surface (or an earlier cut) are dropped, moment matrices
//    recomputed on every such change; all of it but the state transfer works in the rest configuration, so with
//    cutting.conversion_delay_frames 1 it is prepared on workers beside the frame and applied at the next one;
//  - each frame is cutting.exchanges_per_frame coupling intervals: the points advance by MLS (the solver of the
//    scene's backend) with the interface spheres' PBD springs acting on their points (eqs. 11-12), then the PBD
//    spheres advance with each interface sphere moved to the mean displacement of its points (eq. 13).
// When it leaves: the cut spheres' points are re-packed by Algorithm 1 (host/cut/cut_repack.h), interface spheres
// return to PBD with their eq. 13 state, links never cross a cut, the surface is split along the swept surface
// whatever its shape (curved, partial: a slit; CGAL walls, host/cut/cut_surface_state.h) at every cut, the skin
// re-bound across no cut (cutWallTriangles() flags the walls); the nodal points go back to zero. That work runs on
// idle-priority workers (host/cut/cut_stroke_end.h) and is applied cutting.stroke_end_frames frames after the blade
// leaves, the points simulated meanwhile (0: in that frame). With cutting.blade_radius_m > 0 the blade is also a
// contact capsule for the spheres and the nodal points while it is in the tissue. With cutting.open_surface_frames
// N > 0 the surface is also split along the sweep so far on a worker while the blade is in, shown N frames later
// (display only).
// Graspers (close at their first keyframe, drag, release at their last) and probes act on the spheres.
// currentSurface() is the surface moved by the spheres (translation skinning; during a stroke a converted sphere
// moves by eq. 13 of its points; the shown opening's mesh while there is one). FrameReport stages: the PBD
// backend's, cut_sweep, cut_convert (of it cut_convert_{pbd,mls,sample,supports,mls_model,mls_setup,mls_build,
// pbd_build,wait}; cut_convert_prepare, the workers' share), mls_integrate,
// mls_coupling, mls_stress, mls_forces (GPU times per stage; zero on the GPU's graph path), mls_substeps (the
// GPU's graph of substeps), mls_reduce, mls_wall (wall time of the MLS advances), coupling_exchange, cut_repack,
// cut_apply (ms). Counters: spheres, mass_kg,
// cut_spheres_pending, interface_spheres, nodal_points, coupling_springs, coupling_spring_energy_j,
// coupling_exchanges, mls_substeps, mls_isolated_points, mls_regularised_points, supports_cut, cuts_applied,
// sphere_components, links, grasped, nodal_points_last_cut, spheres_added_last_cut, repack_* (groups, boundary /
// medial / middle points, packed, merged, spacing_m), surface_split, surface_components, sweep_ms, convert_ms,
// repack_ms, cut_apply_ms, stroke_end_pending, stroke_end_{worker,split,repack,build,bind}_ms,
// surface_split_failed, surface_opened, surface_open_pending, surface_open_ms, volume_active; stages
// cut_apply_wait, cut_open_wait. The interactive tool (SimulationModel::applyTool): grasp & drag, and mouse scalpel
// strokes (Press begins, Drag extends, Release ends the stroke) cut by the same pipeline. renderLayers(): spheres,
// fixed and grasped spheres, the swept surfaces (applied cuts and the stroke in progress) and, while a stroke is in
// the tissue, the nodal points where they are now.
std::unique_ptr<SimulationModel> makeDissectionSimulation(const CompiledScene& scene, BackendKind backend,
                                                          Precision precision);

}  // namespace inc
