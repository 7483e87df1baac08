// The viewer's layers of a PBD metaball model: spheres, fixed and grasped spheres, grasp forces (RenderLayers).
#pragma once

#include <cstdint>
#include <vector>

#include "host/sim/simulation_model.h"
#include "model/pbd_model.h"

namespace inc {

// Every sphere at its current centre with its current radius (volume preservation changes radii).
template <typename T>
void appendPbdSpheres(const PbdState<T>& s, RenderLayers& out) {
  out.sphere_centres.reserve(out.sphere_centres.size() + s.positions.size());
  for (std::size_t i = 0; i < s.positions.size(); ++i) {
    out.sphere_centres.push_back(Vec3d(s.positions[i]));
    out.sphere_radii.push_back(double(s.radii[i]));
  }
}

// The spheres a fixed region holds: inverse mass 0 (host/assembly/pbd_builders.cpp: rest centre inside a fixed box).
template <typename T>
void appendPbdFixed(const PbdModel<T>& m, const PbdState<T>& s, RenderLayers& out) {
  for (std::size_t i = 0; i < m.size(); ++i)
    if (!(m.inv_mass[i] > T(0))) {
      out.fixed_ids.push_back(std::int32_t(i));
      out.fixed_points.push_back(Vec3d(s.positions[i]));
    }
}

// The grasp of one tool: its attachments `in` (targets at the end of the frame just advanced) hold their
// spheres, which are listed as held. With XPBD each attachment C = x - target, compliance alpha (m/N), is
// projected last in every iteration, so after a substep C + (alpha / h^2) lambda = 0 exactly and the force
// it applies to its sphere is lambda / h^2 = (target - x) / alpha (Macklin et al. 2016, eq. 18 and the force
// f = lambda grad C / h^2). At rest the sum over a tool's spheres balances what holds the tissue up, so a
// block hanging from the grasp pulls the tool with its weight. The tool's arrow, at `tip`, is the tissue's
// reaction: minus that sum. Plain PBD (xpbd false) or rigid attachments (alpha 0) define no force: only
// the held spheres are reported.
template <typename T>
void appendAttachmentLayers(const PbdFrameInput<T>& in, const PbdState<T>& s, bool xpbd, const Vec3d& tip,
                            RenderLayers& out) {
  if (in.attach_ids.empty()) return;
  bool forces = xpbd;
  for (T alpha : in.attach_compliance) forces = forces && alpha > T(0);
  Vec3d total;
  for (std::size_t k = 0; k < in.attach_ids.size(); ++k) {
    const std::int32_t i = in.attach_ids[k];
    const Vec3d x(s.positions[std::size_t(i)]);
    out.held_ids.push_back(i);
    out.held_points.push_back(x);
    if (!forces) continue;
    const Vec3d f = (Vec3d(in.attach_to[k]) - x) * (1.0 / double(in.attach_compliance[k]));
    out.forces.push_back({x, f, ForceArrowKind::Particle});
    total += f;
  }
  if (forces) out.forces.push_back({tip, total * -1.0, ForceArrowKind::Tool});
}

}  // namespace inc
