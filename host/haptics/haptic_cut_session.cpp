// Lockstep haptic cutting session: ticks, cut decisions to the cutting pipeline, frames, topology summaries.
#include "host/haptics/haptic_cut_session.h"

#include <algorithm>
#include <cmath>

#include "model/input_error.h"

namespace inc {

namespace {
std::uint64_t fnv1a(const void* data, std::size_t n, std::uint64_t h) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

// v turned by the unit quaternion q = (w, x, y, z): v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z).
Vec3d rotate(const double q[4], const Vec3d& v) {
  const Vec3d u{q[1], q[2], q[3]};
  const Vec3d t = cross(u, v) * 2.0;
  return v + t * q[0] + cross(u, t);
}
}  // namespace

TopologySummary summarizeTopology(const SimulationModel& sim, const FrameReport& report) {
  TopologySummary s;
  s.particles = sim.particleCount();
  const auto links = report.counters.find("links");
  s.links = links == report.counters.end() ? 0 : std::size_t(links->second);
  const auto cuts = report.counters.find("cuts_applied");
  s.cuts_applied = cuts == report.counters.end() ? 0 : int(cuts->second);
  std::vector<Vec3d> x;
  sim.currentPositions(x);
  s.position_hash = fnv1a(x.data(), x.size() * sizeof(Vec3d), 1469598103934665603ull);
  TriangleMesh surface;
  if (sim.currentSurface(surface)) {
    s.surface_triangles = surface.triangles.size();
    s.position_hash = fnv1a(surface.vertices.data(), surface.vertices.size() * sizeof(Vec3d), s.position_hash);
  }
  return s;
}

HapticCutSession::HapticCutSession(SimulationModel& sim, HapticDevice& device, CuttingTool& tool,
                                   const HapticCutSessionConfig& config)
    : sim_(sim), tool_(tool), config_(config) {
  const char* f = "<haptic cut session>";
  if (!sim_.toolSupport().cut) throw InputError(f, "model", sim_.name() + " cannot be cut by a tool");
  if (!(config_.frame_dt_s > 0.0) || !std::isfinite(config_.frame_dt_s))
    throw InputError(f, "frame_dt_s", "must be > 0");
  if (!(config_.blade_length_m > 0.0) || !std::isfinite(config_.blade_length_m))
    throw InputError(f, "blade_length_m", "must be > 0");
  if (!(norm(config_.blade_axis_device) > 0.0)) throw InputError(f, "blade_axis_device", "must be non-zero");
  config_.blade_axis_device = config_.blade_axis_device * (1.0 / norm(config_.blade_axis_device));
  loop_ = std::make_unique<HapticLoop>(
      device, [this](const ForceRequest& q) { return tool_.tick(q); }, config_.loop, &clock_);
  ticks_per_frame_ = std::max(1, int(std::lround(config_.frame_dt_s / loop_->period_s())));
}

ToolEvent bladeToolEvent(ToolPhase phase, const Vec3d& tip, const double orientation[4], const Vec3d& blade_axis_device,
                         double blade_length_m) {
  ToolEvent e;
  e.kind = ToolKind::Cut;
  e.phase = phase;
  e.tip = tip;
  e.axis = rotate(orientation, blade_axis_device);
  e.blade_length_m = blade_length_m;
  return e;
}

ToolEvent HapticCutSession::bladeEvent(ToolPhase phase, const Vec3d& tip, const double orientation[4]) const {
  return bladeToolEvent(phase, tip, orientation, config_.blade_axis_device, config_.blade_length_m);
}

void HapticCutSession::runFrames(int frames) {
  for (int n = 0; n < frames; ++n) {
    loop_->runTicks(std::uint64_t(ticks_per_frame_));
    SessionFrame fr;
    // The decisions of this frame's ticks, in tick order: they drive the cutting pipeline (section 5).
    CutEvent e;
    while (tool_.events().pop(e)) {
      ++fr.cut_events;
      const ToolResult r =
          sim_.applyTool(bladeEvent(e.start ? ToolPhase::Press : ToolPhase::Release, e.position_m, e.orientation));
      if (!r.supported) messages_.push_back(r.message);
      fr.cut_applied = fr.cut_applied || r.cut_applied;
      cut_open_ = e.start;
    }
    if (cut_open_) {  // the blade's newest pose extends the open stroke's swept surface
      const DeviceSample& s = loop_->records().back().sample;
      const ToolResult r = sim_.applyTool(bladeEvent(ToolPhase::Drag, s.position_m, s.orientation));
      if (!r.supported) messages_.push_back(r.message);
    }
    const FrameReport rep = sim_.advance(config_.frame_dt_s);
    fr.ticks_done = loop_->records().size();
    fr.topology = summarizeTopology(sim_, rep);
    frames_.push_back(fr);
  }
}

}  // namespace inc
