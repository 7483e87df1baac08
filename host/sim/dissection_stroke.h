// A scalpel stroke of the dissection model: the scripted strokes, the stroke in progress and its blade.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/compiled/model_specs.h"
#include "host/cut/cut_nodal_region.h"
#include "host/cut/cut_swept_surface.h"

namespace inc::dissection {

// A scripted stroke: one scalpel tool, cutting from its first keyframe's time to its last.
struct ScriptedStroke {
  ToolSpec tool;
  double start = 0, end = 0;  // s
  bool begun = false, done = false;
};

// The cut in progress: the model when it began (base indices), its swept surface, its nodal points, and where
// each base sphere sits in the PBD model now (-1: converted into points and removed).
struct ActiveStroke {
  MetaballModel base;
  SweptSurface swept;
  std::unique_ptr<NodalRegion> region;
  std::vector<std::int32_t> base_to_pbd, pbd_to_base;
  std::vector<double> base_cell_volume;    // the base PBD model's rest cell volumes (empty: volume preservation off)
  std::vector<double> base_contact_inset;  // the base PBD model's contact insets (empty: the scene has no colliders)
  int scripted = -1;                       // index into the scripted strokes, -1: the mouse's
  std::size_t opened_triangles = 0;        // swept triangles the last surface opening was started with
};

// The scalpel's blade at time t: the segment of tool.length centred on the path position along the path direction.
BladePose scalpelBlade(const ToolSpec& tool, double t);

inline BladePose lerpBlade(const BladePose& a, const BladePose& b, double s) {
  return {a.base + (b.base - a.base) * s, a.tip + (b.tip - a.tip) * s};
}

// The strip the last extendSweptSurface added to `swept` (it had nv vertices and nt triangles before), alone.
SweptSurface newestStrip(const SweptSurface& swept, std::size_t nv, std::size_t nt);

// The PBD model during a stroke: the base spheres that are not cut (interface spheres stay, kinematic), in base
// order, with the links among them (a link never crosses the stroke without entering one of its spheres);
// base_to_kept maps base indices to theirs (-1: cut).
MetaballModel uncutSpheres(const MetaballModel& base, const std::vector<SphereRole>* roles,
                           std::vector<std::int32_t>& base_to_kept);

// How long a frame waits for an idle-priority worker's due result before computing it itself (ms): as long as
// computing it took the last time (at least 10 ms; 50 before any). Then the worst case is about twice the work
// instead of however long a busy machine starves the worker (its OpenMP threads stay idle even when boosted);
// the result is the same either way, so runs stay deterministic.
inline double workerPatienceMs(double last_ms) { return last_ms > 0 ? std::min(std::max(last_ms, 10.0), 500.0) : 50.0; }

}  // namespace inc::dissection
