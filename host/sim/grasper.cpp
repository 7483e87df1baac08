// Tool poses along keyframed paths, probe capsules and the grasper's catch/hold/release.
#include "host/sim/grasper.h"

#include <cmath>

#include "model/input_error.h"
#include "physics/pbd_grasp.h"

namespace inc {

ToolPose toolPoseAt(const ToolSpec& tool, double t) {
  if (tool.path.empty()) throw InputError("tool " + tool.name, "path", "needs at least one keyframe");
  const auto& p = tool.path;
  ToolPose pose;
  if (t <= p.front().t) {
    pose.position = p.front().position;
    pose.direction = p.front().direction;
  } else if (t >= p.back().t) {
    pose.position = p.back().position;
    pose.direction = p.back().direction;
  } else {
    std::size_t k = 0;
    while (k + 1 < p.size() && p[k + 1].t < t) ++k;
    const double span = p[k + 1].t - p[k].t;
    const double s = span > 0 ? (t - p[k].t) / span : 1.0;
    pose.position = p[k].position + (p[k + 1].position - p[k].position) * s;
    pose.direction = p[k].direction + (p[k + 1].direction - p[k].direction) * s;
  }
  const double n = norm(pose.direction);
  pose.direction = n > 0 ? pose.direction * (1.0 / n) : Vec3d(0, 0, -1);
  return pose;
}

pbd::CapsuleCollider<double> toolCapsule(const ToolSpec& tool, const ToolPose& pose) {
  pbd::CapsuleCollider<double> c;
  c.a = pose.position;
  c.b = pose.position - pose.direction * tool.length;
  c.radius = tool.radius;
  c.friction = tool.friction;
  return c;
}

Grasper::Grasper(const ToolSpec& tool, double reach_m, double compliance)
    : tool_(tool), reach_(reach_m), compliance_(compliance) {
  const std::string f = "tool " + tool.name;
  if (tool.path.empty()) throw InputError(f, "path", "needs at least one keyframe");
  if (!(reach_m > 0) || !std::isfinite(reach_m)) throw InputError(f, "radius", "grasp reach must be > 0");
  if (!(compliance >= 0) || !std::isfinite(compliance)) throw InputError(f, "compliance", "must be finite and >= 0");
  close_t_ = tool.path.front().t;
  release_t_ = tool.path.back().t;
}

int Grasper::grasp(const Vec3d& tip, const std::vector<Vec3d>& centers, const std::vector<double>& radii,
                   const std::vector<std::uint8_t>& movable) {
  ids_.clear();
  offsets_.clear();
  for (std::size_t i = 0; i < centers.size(); ++i) {
    if (!movable[i]) continue;
    if (pbd::inGraspReach(centers[i], radii[i], tip, reach_)) {
      ids_.push_back(std::int32_t(i));
      offsets_.push_back(centers[i] - tip);
    }
  }
  holding_ = !ids_.empty();
  if (!holding_) finished_ = true;
  return int(ids_.size());
}

void Grasper::remap(const std::vector<std::int32_t>& new_index) {
  std::vector<std::int32_t> ids;
  std::vector<Vec3d> offsets;
  for (std::size_t k = 0; k < ids_.size(); ++k) {
    const std::int32_t i = ids_[k];
    if (i < 0 || std::size_t(i) >= new_index.size() || new_index[std::size_t(i)] < 0) continue;
    ids.push_back(new_index[std::size_t(i)]);
    offsets.push_back(offsets_[k]);
  }
  ids_ = std::move(ids);
  offsets_ = std::move(offsets);
  if (holding_ && ids_.empty()) release();
}

void Grasper::release() {
  holding_ = false;
  finished_ = true;
  ids_.clear();
  offsets_.clear();
}

}  // namespace inc
