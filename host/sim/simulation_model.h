// The interface every simulated model (MLS solid, metaball organ, tearing sheet, ...) offers the runner.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "host/io/mesh.h"
#include "model/backend.h"
#include "model/stage_timing.h"
#include "physics/vec3.h"

namespace inc {

// What one frame did; the runner writes it as a row of metrics.csv and checks it.
struct FrameReport {
  int substeps = 0;
  double dt = 0.0;  // s, substep actually used
  std::vector<StageTime> stages;
  double kinetic_energy = 0.0;    // J
  double elastic_energy = 0.0;    // J (strain or constraint energy)
  double potential_energy = 0.0;  // J, gravity, relative to rest
  double max_displacement = 0.0;  // m, from rest
  bool finite = true;             // false: a NaN/Inf appeared; failure_* say where
  std::string failure_stage;
  std::int64_t failure_particle = -1;
  // A frame the model refused without stepping (finite false, stage "substep_limit"): it would cost more than the
  // frame budget (model/frame_budget.h). A retry at a smaller step cannot help; failure_reason says what to change.
  bool refused = false;
  std::string failure_reason;
  std::map<std::string, double> counters;  // model-specific ("degenerate_neighbourhoods", "broken_bonds", ...)
  // A model that runs a haptic loop reports its rate and period p99 as counters "haptic_hz" and
  // "haptic_p99_ms" (the viewer's Haptics plots).
};

// Marks `r` as a frame the model refused without stepping, for `reason` (model/frame_budget.h's texts).
inline void refuseFrame(FrameReport& r, std::string reason) {
  r.finite = false;
  r.refused = true;
  r.failure_stage = "substep_limit";
  r.failure_particle = -1;
  r.failure_reason = std::move(reason);
}

// The interactive tool (the viewer's mouse): what a model can do with it.
struct ToolSupport {
  bool grasp = false;  // grasp & drag: particles / spheres near the tip follow it until released
  bool cut = false;    // a scalpel stroke (successive blade poses) cuts the model when it ends
};

enum class ToolKind { Grasp, Cut };
enum class ToolPhase {
  Press,    // grasp: catch what lies within radius_m of the tip; cut: the stroke's first blade pose
  Drag,     // grasp: the caught region's target follows the tip; cut: the next blade pose
  Release,  // grasp: let go; cut: the last blade pose, then the cut is applied (as the scripted scalpel's)
};

// One tool event in world coordinates (m). The blade of a cut is the segment of blade_length_m centred on
// `tip` along `axis` (the viewer uses its view direction).
struct ToolEvent {
  ToolKind kind = ToolKind::Grasp;
  ToolPhase phase = ToolPhase::Press;
  Vec3d tip;
  Vec3d axis{0, 0, -1};
  double radius_m = 0.005;       // grasp reach around the tip
  double blade_length_m = 0.05;  // cut
};

struct ToolResult {
  bool supported = false;    // false: this model cannot do this (message says why); nothing changed
  int grasped = 0;           // particles / spheres held after the event
  bool cut_applied = false;  // a Release ended a stroke that swept a surface: its cut is applied (now, or
                             // cutting.stroke_end_frames frames later)
  std::string message;
};

// What a model can show besides its surface and particles (the viewer's layers). World metres, current
// configuration. Every part is optional: an empty vector means the model has no such data. Ids index the
// particles of currentPositions(); a model that reports spheres has sphere i = particle i.
enum class ForceArrowKind : std::uint8_t {
  Tool,      // the tissue's reaction on a tool (grasp), drawn at the tool tip: what a hand on it would feel
  Particle,  // an external force a tool or a support applies to one particle
};
struct ForceArrow {
  Vec3d origin;   // m
  Vec3d force_n;  // N
  ForceArrowKind kind = ForceArrowKind::Particle;
};
struct RenderLayers {
  std::vector<Vec3d> sphere_centres;    // metaball spheres (m) ...
  std::vector<double> sphere_radii;     // ... and their radii (m), one per centre
  std::vector<Vec3d> nodal_points;      // MLS nodal points (m)
  std::vector<std::int32_t> fixed_ids;  // particles a fixed region holds (Dirichlet) ...
  std::vector<Vec3d> fixed_points;      // ... and where they are (m)
  std::vector<std::int32_t> held_ids;   // particles a tool holds now (grasped, prescribed) ...
  std::vector<Vec3d> held_points;       // ... and where they are (m)
  TriangleMesh swept_surface;           // the scalpel's swept cut surface(s) (m)
  TriangleMesh colliders;  // the scene's static colliders (host/compiled/scene_colliders.h colliderMesh) (m)
  std::vector<ForceArrow> forces;
};

class SimulationModel {
 public:
  virtual ~SimulationModel() = default;
  virtual std::string name() const = 0;
  virtual BackendKind backend() const = 0;
  virtual std::size_t particleCount() const = 0;
  // One line on how the model was built that a user should see (e.g. stragglers linked in its sphere fill);
  // empty when there is nothing to say.
  virtual std::string buildNote() const { return {}; }
  // Advances one frame of frame_dt seconds, substepping as stability requires. Must not throw on bad
  // physics: report finite == false with the stage and particle instead.
  virtual FrameReport advance(double frame_dt) = 0;
  // Keep / return to the last good state (the runner's guard rolls back and retries with a smaller step).
  virtual void saveCheckpoint() = 0;
  virtual void restoreCheckpoint() = 0;
  // Scale the stable-step safety factor (the guard halves it on a retry).
  virtual void scaleTimeStep(double factor) = 0;
  // Current particle positions (for output and drawing) and the surface, if the model has one.
  virtual void currentPositions(std::vector<Vec3d>& out) const = 0;
  virtual bool currentSurface(TriangleMesh& /*out*/) const { return false; }
  virtual MemoryReport memory() const = 0;

  // --- The interactive tool. Called between frames on the thread that advances the model (the viewer
  // queues the mouse's events and applies them before the next advance()). The effect of a grasp shows in
  // the following advance() frames (the held region moves to the tip over the frame); a cut's Release
  // changes the topology at once. Models that cannot do it keep the defaults: nothing is supported.
  virtual ToolSupport toolSupport() const { return {}; }
  virtual ToolResult applyTool(const ToolEvent& /*event*/) {
    ToolResult r;
    r.message = name() + " does not support this tool";
    return r;
  }
  // One flag per triangle of currentSurface(): 1 for a cut wall (drawn in the cut-wall colour). Empty
  // (the default): no triangle is a cut wall.
  virtual void cutWallTriangles(std::vector<std::uint8_t>& out) const { out.clear(); }
  // The geometry of the viewer's extra layers (spheres, nodal points, fixed and held particles, swept
  // surface, force arrows) at the current state. Default: none.
  virtual void renderLayers(RenderLayers& out) const { out = RenderLayers{}; }
};

}  // namespace inc
