// The interactive (mouse) tool's shared logic: the PBD grasp that follows a moving target, blade poses from
// tool events, the rest-configuration point under a deformed one, and sphere-graph components.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/cut/cut_swept_surface.h"
#include "host/sim/grasper.h"
#include "host/sim/simulation_model.h"
#include "model/pbd_model.h"
#include "physics/vec3.h"

namespace inc {

// The mouse grasp of a PBD sphere model, built on the scripted Grasper: Press catches the movable spheres
// whose ball reaches within radius_m of the tip (physics/pbd_grasp.h inGraspReach), each keeps its offset
// from the tip; while held, every frame attaches them (compliance 1e-6 m/N, as the scripted grasper) to
// targets moving from the tip at the previous frame to the tip of the latest Drag; Release lets go.
class PbdMouseGrasp {
 public:
  // Handles a Grasp event (kind must be ToolKind::Grasp). Returns supported = true and the count held.
  ToolResult apply(const ToolEvent& e, const std::vector<Vec3d>& centres, const std::vector<double>& radii,
                   const std::vector<std::uint8_t>& movable);
  bool holding() const { return grasper_ && grasper_->holding(); }
  int held() const { return grasper_ ? int(grasper_->grasped().size()) : 0; }
  void release();  // also used when the topology changes (sphere indices no longer mean the same)

  // This frame's attachments (no-op unless holding); call frameDone() after the frame was advanced.
  template <typename T>
  void appendAttachments(PbdFrameInput<T>& in) const {
    if (holding()) grasper_->appendAttachments(from_, to_, in);
  }
  void frameDone() { from_ = to_; }
  const Vec3d& tip() const { return to_; }  // where the held spheres' targets are anchored now (m)

 private:
  std::optional<Grasper> grasper_;
  Vec3d from_, to_;  // tip at the start of the next frame and its target at the frame's end (m)
};

// The blade of a Cut event: the segment of blade_length_m centred on the tip along the unit axis.
// Throws InputError("tool", ...) for a non-finite tip, a zero axis or a blade length <= 0.
BladePose bladeFromToolEvent(const ToolEvent& e);

// Where a point of the deformed configuration sits in the rest configuration: p minus the displacement
// (current - rest) interpolated from the k nearest particles by inverse distance (weights 1 / (d + eps)).
// For a tool on or near a body this is the material point under it (exact for a translated body).
Vec3d restPointFromCurrent(const Vec3d& p, const std::vector<Vec3d>& current, const std::vector<Vec3d>& rest,
                           int k = 4);

}  // namespace inc

namespace inc {

// Appends the mouse grasp's attachments to `in`, skipping spheres another (scripted) grasper already holds
// this frame (PbdFrameInput needs unique attachment ids).
template <typename T>
void appendMouseAttachments(const PbdMouseGrasp& grasp, PbdFrameInput<T>& in) {
  if (!grasp.holding()) return;
  PbdFrameInput<T> mine;
  grasp.appendAttachments(mine);
  for (std::size_t k = 0; k < mine.attach_ids.size(); ++k) {
    if (std::find(in.attach_ids.begin(), in.attach_ids.end(), mine.attach_ids[k]) != in.attach_ids.end()) continue;
    in.attach_ids.push_back(mine.attach_ids[k]);
    in.attach_from.push_back(mine.attach_from[k]);
    in.attach_to.push_back(mine.attach_to[k]);
    in.attach_compliance.push_back(mine.attach_compliance[k]);
  }
}

}  // namespace inc
