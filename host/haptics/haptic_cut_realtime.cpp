// Real-time haptic cutting session: loop thread deciding (eqs. 15-16), decisions applied between simulation frames.
#include "host/haptics/haptic_cut_realtime.h"

#include <cmath>

#include "host/haptics/haptic_cut_session.h"
#include "model/input_error.h"

namespace inc {

RealtimeHapticCutSession::RealtimeHapticCutSession(HapticDevice& device, CuttingTool& tool,
                                                   const RealtimeCutConfig& config, HapticClock* clock)
    : tool_(tool), config_(config) {
  const char* f = "<real-time haptic cut session>";
  if (!(config_.blade_length_m > 0.0) || !std::isfinite(config_.blade_length_m))
    throw InputError(f, "blade_length_m", "must be > 0");
  if (!(norm(config_.blade_axis_device) > 0.0) || !isFinite(config_.blade_axis_device))
    throw InputError(f, "blade_axis_device", "must be non-zero");
  config_.blade_axis_device = config_.blade_axis_device * (1.0 / norm(config_.blade_axis_device));
  loop_ = std::make_unique<HapticLoop>(
      device, [this](const ForceRequest& q) { return link_.stamp(tool_.tick(q), q.t_s); }, config_.loop, clock);
}

RealtimeHapticCutSession::~RealtimeHapticCutSession() { stop(); }

void RealtimeHapticCutSession::start() {
  link_.setDataTime(0.0);  // a first frame that never ends fades the force like any later stall
  loop_->start();
}

void RealtimeHapticCutSession::stop() { loop_->stop(); }

const HapticStatus& RealtimeHapticCutSession::newestStatus() {
  loop_->status().update();
  return loop_->status().front();
}

CutFeed RealtimeHapticCutSession::applyDecisions(SimulationModel& sim) {
  if (!sim.toolSupport().cut)
    throw InputError("<real-time haptic cut session>", "model", sim.name() + " cannot be cut by a tool");
  if (last_sim_ != &sim) cut_open_ = false;  // a rebuilt model has no open stroke
  last_sim_ = &sim;
  CutFeed feed;
  CutEvent e;
  while (tool_.events().pop(e)) {
    ++feed.events;
    ++decisions_;
    const ToolResult r =
        sim.applyTool(bladeToolEvent(e.start ? ToolPhase::Press : ToolPhase::Release, e.position_m, e.orientation,
                                     config_.blade_axis_device, config_.blade_length_m));
    if (!r.supported) messages_.push_back(r.message);
    if (r.cut_applied) ++cuts_applied_;
    feed.cut_applied = feed.cut_applied || r.cut_applied;
    cut_open_ = e.start && r.supported;
  }
  if (cut_open_) {  // the blade's newest pose extends the open stroke's swept surface
    const HapticStatus& s = newestStatus();
    const ToolResult r = sim.applyTool(bladeToolEvent(ToolPhase::Drag, s.sample.position_m, s.sample.orientation,
                                                      config_.blade_axis_device, config_.blade_length_m));
    if (!r.supported) messages_.push_back(r.message);
  }
  return feed;
}

FrameReport RealtimeHapticCutSession::runFrame(SimulationModel& sim, double frame_dt_s) {
  applyDecisions(sim);
  FrameReport rep = sim.advance(frame_dt_s);
  const HapticWindow w = frameDone();
  rep.counters["haptic_hz"] = w.rate_hz;
  rep.counters["haptic_p99_ms"] = w.p99_ms;
  rep.counters["haptic_cut_decisions"] = decisions_;
  return rep;
}

}  // namespace inc
