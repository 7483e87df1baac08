// Scripted tools for the PBD organ: tool poses along a keyframed path, probe capsules, and the grasper that attaches
// the spheres it closes on.
#pragma once

#include <cstdint>
#include <vector>

#include "host/compiled/model_specs.h"
#include "model/pbd_model.h"
#include "physics/pbd_collision.h"
#include "physics/vec3.h"

namespace inc {

struct ToolPose {
  Vec3d position;             // m, tool tip
  Vec3d direction{0, 0, -1};  // unit, where the tool points
};

// Piecewise-linear pose along tool.path at time t (s), held at the first/last keyframe outside the path's
// time span; the direction is interpolated linearly and re-normalised. Throws InputError on an empty path.
ToolPose toolPoseAt(const ToolSpec& tool, double t);

// The tool's contact shape: a capsule from the tip back along the shaft (tip - length * direction).
pbd::CapsuleCollider<double> toolCapsule(const ToolSpec& tool, const ToolPose& pose);

// A grasper scripted by its path: it closes at the first keyframe's time, catching every movable sphere
// within `reach` of its tip (physics/pbd_grasp.h), drags the caught spheres along with the tip through
// compliant attachments (physics/pbd_block.h projectAttachment), and releases them at the last keyframe's
// time. While open it is a contact capsule like a probe; while holding it is not (the caught tissue sits
// between its jaws).
class Grasper {
 public:
  // reach_m > 0: jaw ball radius; compliance >= 0 (m/N) of each attachment. Throws InputError.
  Grasper(const ToolSpec& tool, double reach_m, double compliance);

  double closeTime() const { return close_t_; }
  double releaseTime() const { return release_t_; }
  bool holding() const { return holding_; }
  bool finished() const { return finished_; }
  const std::vector<std::int32_t>& grasped() const { return ids_; }
  const ToolSpec& tool() const { return tool_; }

  // Attaches the spheres with movable[i] != 0 in reach of `tip`; returns how many. A grasp that catches
  // nothing leaves the grasper open (and finished: a scripted grasper closes once).
  int grasp(const Vec3d& tip, const std::vector<Vec3d>& centers, const std::vector<double>& radii,
            const std::vector<std::uint8_t>& movable);
  void release();
  // The sphere indices changed (a cut rebuilt the model): old index i is now new_index[i]; spheres that are gone
  // (-1) drop out of the grasp, which lets go when nothing is left.
  void remap(const std::vector<std::int32_t>& new_index);

  // The frame's attachments for a tip moving from tip_from to tip_to (no-op unless holding).
  template <typename T>
  void appendAttachments(const Vec3d& tip_from, const Vec3d& tip_to, PbdFrameInput<T>& in) const {
    if (!holding_) return;
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      in.attach_ids.push_back(ids_[k]);
      in.attach_from.push_back(Vec3<T>(tip_from + offsets_[k]));
      in.attach_to.push_back(Vec3<T>(tip_to + offsets_[k]));
      in.attach_compliance.push_back(T(compliance_));
    }
  }

 private:
  ToolSpec tool_;
  double reach_ = 0, compliance_ = 0, close_t_ = 0, release_t_ = 0;
  bool holding_ = false, finished_ = false;
  std::vector<std::int32_t> ids_;
  std::vector<Vec3d> offsets_;  // centre - tip at the grasp (m)
};

// The tool capsule in the solver's precision.
template <typename T>
pbd::CapsuleCollider<T> capsuleAs(const pbd::CapsuleCollider<double>& c) {
  pbd::CapsuleCollider<T> o;
  o.a = Vec3<T>(c.a);
  o.b = Vec3<T>(c.b);
  o.radius = T(c.radius);
  o.friction = T(c.friction);
  return o;
}

// A scripted tool's part of the frame input over [t0, t1]: a holding grasper's attachments, an open one's
// capsule (it is a contact shape like a probe).
template <typename T>
void appendGrasperInput(const Grasper& g, double t0, double t1, PbdFrameInput<T>& in) {
  const ToolPose a = toolPoseAt(g.tool(), t0), b = toolPoseAt(g.tool(), t1);
  if (g.holding()) {
    g.appendAttachments(a.position, b.position, in);
  } else {
    in.tools_from.push_back(capsuleAs<T>(toolCapsule(g.tool(), a)));
    in.tools_to.push_back(capsuleAs<T>(toolCapsule(g.tool(), b)));
  }
}

// Probes: contact capsules moving over [t0, t1].
template <typename T>
void appendProbeInputs(const std::vector<ToolSpec>& probes, double t0, double t1, PbdFrameInput<T>& in) {
  for (const ToolSpec& t : probes) {
    in.tools_from.push_back(capsuleAs<T>(toolCapsule(t, toolPoseAt(t, t0))));
    in.tools_to.push_back(capsuleAs<T>(toolCapsule(t, toolPoseAt(t, t1))));
  }
}

}  // namespace inc
