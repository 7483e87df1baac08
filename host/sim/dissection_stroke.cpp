// The dissection's strokes: scripted and mouse scalpels begin, extend (the sweep and the spheres it enters) and end.
#include "host/sim/dissection_stroke.h"

#include <algorithm>
#include <chrono>

#include "base/elapsed_ms.h"
#include "host/sim/dissection_simulation_impl.h"

namespace inc::dissection {

BladePose scalpelBlade(const ToolSpec& tool, double t) {
  const ToolPose pose = toolPoseAt(tool, t);
  const Vec3d d = pose.direction * (0.5 * tool.length / std::max(norm(pose.direction), 1e-300));
  return {pose.position - d, pose.position + d};
}

SweptSurface newestStrip(const SweptSurface& swept, std::size_t nv, std::size_t nt) {
  SweptSurface fresh;
  fresh.vertices.assign(swept.vertices.end() - 4, swept.vertices.end());
  for (std::size_t t = nt; t < swept.triangles.size(); ++t) {
    const auto& tri = swept.triangles[t];
    fresh.triangles.push_back({tri[0] - int(nv) + 2, tri[1] - int(nv) + 2, tri[2] - int(nv) + 2});
  }
  return fresh;
}

MetaballModel uncutSpheres(const MetaballModel& base, const std::vector<SphereRole>* roles,
                           std::vector<std::int32_t>& base_to_kept) {
  MetaballModel m;
  base_to_kept.assign(base.size(), -1);
  for (std::size_t b = 0; b < base.size(); ++b) {
    if (roles && (*roles)[b] == SphereRole::Cut) continue;
    base_to_kept[b] = std::int32_t(m.size());
    m.rest_centers.push_back(base.rest_centers[b]);
    m.rest_radii.push_back(base.rest_radii[b]);
    m.masses.push_back(base.masses[b]);
  }
  for (std::size_t l = 0; l < base.links.size(); ++l) {
    const std::int32_t i = base_to_kept[std::size_t(base.links[l][0])], j = base_to_kept[std::size_t(base.links[l][1])];
    if (i < 0 || j < 0) continue;
    m.links.push_back({std::min(i, j), std::max(i, j)});
    m.link_rest_lengths.push_back(base.link_rest_lengths[l]);
  }
  return m;
}

// The scripted scalpels over the frame [t0, t1]: a stroke begins at its start (ending any other first), extends to
// the blade at the frame's end, and ends at its end. A mouse stroke that began since takes the blade: it has
// applied the scripted stroke's cut so far (completeStroke), and the scripted stroke is over.
template <typename T>
void DissectionSimulation<T>::scriptedStrokes(double t0, double t1) {
  for (std::size_t k = 0; k < strokes_.size(); ++k) {
    ScriptedStroke& s = strokes_[k];
    if (s.done || t1 < s.start) continue;
    if (s.begun && !(active_ && active_->scripted == int(k))) {
      s.done = true;
      continue;
    }
    const auto c0 = std::chrono::steady_clock::now();
    if (!s.begun) {
      completeStroke();  // a mouse stroke still open, or a stroke end still in the making, is applied here
      s.begun = true;
      beginStroke(scalpelBlade(s.tool, std::max(t0, s.start)), int(k));
    }
    extendStroke(scalpelBlade(s.tool, std::min(t1, s.end)));
    if (t1 < s.end) frame_blade_ = {true, scalpelBlade(s.tool, std::max(t0, s.start)), scalpelBlade(s.tool, t1)};
    timers_.sweep_ms += msSince(c0) - last_convert_ms_;
    timers_.convert_ms += last_convert_ms_;
    if (t1 >= s.end) {
      s.done = true;
      const auto c1 = std::chrono::steady_clock::now();
      endStroke();
      timers_.apply_ms += msSince(c1);
    }
  }
}

// The mouse scalpel: each blade pose is taken back to the rest configuration (restPointFromCurrent: the material
// point under it) and extends the stroke exactly as the scripted scalpel does (spheres it reaches become nodal
// points, simulated in the frames that follow); Press begins a stroke, Release ends it (re-packing).
template <typename T>
void DissectionSimulation<T>::mouseStroke(const ToolEvent& e, const std::vector<Vec3d>& x, ToolResult& res) {
  const BladePose world = bladeFromToolEvent(e);
  if (e.phase == ToolPhase::Press) mouse_blade_from_ = world;  // the blade's motion starts here
  mouse_blade_to_ = world;
  const BladePose rest{restPointFromCurrent(world.base, x, spheres_.rest_centers),
                       restPointFromCurrent(world.tip, x, spheres_.rest_centers)};
  const auto c0 = std::chrono::steady_clock::now();
  if (e.phase == ToolPhase::Press || !active_ || ending_ || active_->scripted >= 0) {
    completeStroke();
    beginStroke(rest, -1);
  } else {
    extendStroke(rest);
  }
  mouse_convert_ms_ += msSince(c0);
  if (e.phase == ToolPhase::Release) {
    const auto c1 = std::chrono::steady_clock::now();
    const bool swept = !active_->swept.empty();
    endStroke();
    if (swept)
      res.cut_applied = true;
    else
      res.message = "the stroke swept no surface (the blade did not move)";
    mouse_cut_ms_ += msSince(c1);
  }
}

template <typename T>
void DissectionSimulation<T>::beginStroke(const BladePose& pose, int scripted) {
  active_ = std::make_unique<ActiveStroke>();
  active_->scripted = scripted;
  active_->base = spheres_;
  active_->swept.vertices = {pose.base, pose.tip};
  active_->base_to_pbd.resize(spheres_.size());
  active_->pbd_to_base.resize(spheres_.size());
  for (std::size_t i = 0; i < spheres_.size(); ++i) active_->base_to_pbd[i] = active_->pbd_to_base[i] = std::int32_t(i);
  // The base model's rest cell volumes: a stroke rebuild reuses those of spheres that lost no linked neighbour.
  active_->base_cell_volume.assign(model_.rest_cell_volume.begin(), model_.rest_cell_volume.end());
  active_->base_contact_inset.assign(model_.contact_inset.begin(), model_.contact_inset.end());
  last_convert_ms_ = 0;
}

// Extends the swept surface to `pose`; spheres the new strip enters become nodal points (with their PBD-role
// neighbours as interface spheres), or, when none does, supports crossing the new strip are cut
// (launchConversion). The time it took is last_convert_ms_.
template <typename T>
void DissectionSimulation<T>::extendStroke(const BladePose& pose) {
  last_convert_ms_ = 0;
  ActiveStroke& a = *active_;
  const std::size_t nv = a.swept.vertices.size(), nt = a.swept.triangles.size();
  if (norm(pose.base - a.swept.vertices[nv - 2]) <= 1e-9 && norm(pose.tip - a.swept.vertices[nv - 1]) <= 1e-9) return;
  const auto c0 = std::chrono::steady_clock::now();
  applyConversion();  // one still pending (a mouse stroke's last pose): in before this strip is looked at
  extendSweptSurface(a.swept, pose);
  if (a.swept.triangles.size() == nt) {
    last_convert_ms_ = msSince(c0);
    return;
  }
  auto pc = std::make_unique<PendingConversion<T>>();
  pc->fresh = newestStrip(a.swept, nv, nt);
  std::vector<std::int32_t> hit = spheresEntered(pc->fresh);
  if (hit.empty() && !(a.region && a.region->active())) {
    last_convert_ms_ = msSince(c0);
    return;
  }
  if (!a.region) a.region = std::make_unique<NodalRegion>(a.base, regionSettings(), earlierCuts());
  launchConversion(std::move(pc), std::move(hit));
  last_convert_ms_ = msSince(c0);
}

// The base spheres `strip` enters that are not cut already.
template <typename T>
std::vector<std::int32_t> DissectionSimulation<T>::spheresEntered(const SweptSurface& strip) const {
  const ActiveStroke& a = *active_;
  std::vector<std::int32_t> hit = findCutSpheres(strip, a.base.rest_centers, a.base.rest_radii);
  if (a.region)
    hit.erase(
        std::remove_if(hit.begin(), hit.end(), [&](std::int32_t b) { return a.region->role(b) == SphereRole::Cut; }),
        hit.end());
  return hit;
}

// Ends whatever stroke there is and applies its end now (a new stroke begins).
template <typename T>
void DissectionSimulation<T>::completeStroke() {
  if (!active_) return;
  if (!ending_) endStroke();
  if (ending_) applyStrokeEnd();
}

template <typename T>
std::vector<const SweptSurface*> DissectionSimulation<T>::earlierCuts() const {
  std::vector<const SweptSurface*> out;
  for (const SweptSurface& c : earlier_cuts_) out.push_back(&c);
  return out;
}

#define INC_DISSECTION_STROKE(T)                                                                                \
  template void DissectionSimulation<T>::scriptedStrokes(double, double);                                       \
  template void DissectionSimulation<T>::mouseStroke(const ToolEvent&, const std::vector<Vec3d>&, ToolResult&); \
  template void DissectionSimulation<T>::beginStroke(const BladePose&, int);                                    \
  template void DissectionSimulation<T>::extendStroke(const BladePose&);                                        \
  template std::vector<std::int32_t> DissectionSimulation<T>::spheresEntered(const SweptSurface&) const;        \
  template void DissectionSimulation<T>::completeStroke();                                                      \
  template std::vector<const SweptSurface*> DissectionSimulation<T>::earlierCuts() const;
INC_DISSECTION_STROKE(float)
INC_DISSECTION_STROKE(double)
#undef INC_DISSECTION_STROKE

}  // namespace inc::dissection
