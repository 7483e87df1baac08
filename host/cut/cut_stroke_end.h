// The rest-configuration work of a stroke's end (Algorithm 1, the surface split, the skin binding): a pure function
// of inputs fixed when the blade leaves, so that a worker can compute it while the nodal points are still simulated.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "base/background_task.h"
#include "host/assembly/metaball_model.h"
#include "host/assembly/skin_binding.h"
#include "host/cut/cut_repack.h"
#include "host/cut/cut_surface_state.h"
#include "host/cut/cut_swept_surface.h"

namespace inc {

// Everything a stroke's end reads. Nothing here depends on where the points or spheres are now: the state transfer
// (new spheres from their points' displacements, interface spheres by eq. 13) is the caller's, when it applies the
// result. The pointers must stay valid and unchanged until computeStrokeEnd returns.
struct StrokeEndInput {
  MetaballModel kept;              // the stroke's base spheres that were not cut (PBD and interface), their links
  bool repack = false;             // the blade converted spheres: `points` holds them (else nothing is re-packed)
  RepackPoints points;             // the region's points, rest configuration (NodalRegion::repackPoints)
  RepackSettings settings;         // Algorithm 1's settings; earlier_cuts is filled from `cuts`
  std::vector<SweptSurface> cuts;  // every cut in the order made, this stroke's last (rest configuration)
  // The surface before this cut (read only; shared, so that a computation the caller gave up waiting for may finish
  // on its worker while the caller has gone on to another surface).
  std::shared_ptr<const CutSurfaceState> surface;
  int skin_k = 4;  // spheres per surface vertex (at most the new model's size)
  // A mouse or haptic stroke: a blade path whose sweep the surface split refuses (one turning back over itself)
  // leaves the surface unsplit for this cut (split_failure says why; spheres, points and links are cut all the
  // same) instead of failing the run. A scripted path is the scene's: there it stays an error naming the file.
  bool interactive = false;
  std::string file;  // for error messages
};

struct StrokeEndResult {
  MetaballModel spheres;  // kept, then the re-packed spheres with their links (= kept if !repacked)
  bool repacked = false;
  RepackResult repack;         // owner[i]: the new sphere (index among the re-packed ones) point i went to
  CutSurfaceState surface;     // after the split (a copy of the input state where the blade crossed nothing)
  bool split = false;          // the blade crossed the surface and the split succeeded
  int surface_components = 0;  // of the split surface (its own output check); valid when split
  std::string split_failure;   // why the surface was left unsplit (empty: split, or not crossed)
  SkinBinding skin;            // the surface bound to `spheres`, across every cut including this one
  int sphere_components = 0;   // of `spheres`' link graph
  double repack_ms = 0, build_ms = 0, split_ms = 0, bind_ms = 0, total_ms = 0;  // wall times of the parts
};

// For tests: when set, the dissection's idle-priority tasks (a stroke's end, a surface opening;
// host/sim/dissection_simulation.cpp) first call it on their worker, so a test can hold them as a busy machine would
// starve them. Empty in normal use.
inline std::function<void()>& idleWorkerGate() {
  static std::function<void()> gate;
  return gate;
}

// Splits the surface on `beside` while this thread re-packs and then calls `build(spheres)` (the caller's own
// model build, for example its PBD constraints, timed as build_ms); then binds the skin across every cut and counts
// the sphere graph's components. Deterministic: the same input gives the same result on any thread, at any time.
// Rethrows what the split, the re-pack, the build or the binding threw (after both halves have stopped).
StrokeEndResult computeStrokeEnd(const StrokeEndInput& in, BackgroundTask& beside,
                                 const std::function<void(const MetaballModel&)>& build);

}  // namespace inc
