// Real-time haptic cutting session: loop thread deciding (eqs. 15-16), decisions applied between simulation frames.
#include "host/haptics/haptic_cut_realtime.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

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
  if (!(config_.frame_dt_s > 0.0) || !std::isfinite(config_.frame_dt_s))
    throw InputError(f, "frame_dt_s", "must be > 0");
  if (!(config_.max_wait_s >= 0.0) || !std::isfinite(config_.max_wait_s))
    throw InputError(f, "max_wait_s", "must be >= 0");
  if (!(config_.max_lag_s >= 0.0) || !std::isfinite(config_.max_lag_s))
    throw InputError(f, "max_lag_s", "must be >= 0");
  config_.blade_axis_device = config_.blade_axis_device * (1.0 / norm(config_.blade_axis_device));
  samples_ = std::make_unique<SampleQueue>();
  // The tool's decisions of a tick are queued before its pose: a frame that has the pose has the decisions.
  loop_ = std::make_unique<HapticLoop>(
      device,
      [this](const ForceRequest& q) {
        const ForceResult r = link_.stamp(tool_.tick(q), q.t_s);
        BladeSample s;
        s.tick = q.tick;
        s.position_m = q.sample.position_m;
        for (int k = 0; k < 4; ++k) s.orientation[k] = q.sample.orientation[k];
        if (!samples_->push(s)) {
          dropped_samples_.fetch_add(1, std::memory_order_relaxed);
          ticks_dropped_through_.store(q.tick + 1, std::memory_order_release);
        }
        return r;
      },
      config_.loop, clock);
  ticks_per_frame_ = std::uint64_t(std::max(1L, std::lround(config_.frame_dt_s / loop_->period_s())));
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

// max_lag_s > 0: when the loop's newest tick is more than max_lag_s past end_tick, the frame ends at the last frame
// boundary before it instead (the ticks in between are still applied in order, by this frame).
std::uint64_t RealtimeHapticCutSession::skipAheadWhenLagging(std::uint64_t end_tick) {
  if (!(config_.max_lag_s > 0.0)) return end_tick;
  const std::uint64_t newest_end = newestStatus().tick + 1;
  const auto max_lag = std::uint64_t(std::llround(config_.max_lag_s / loop_->period_s()));
  if (newest_end <= end_tick + max_lag) return end_tick;
  frames_ = newest_end / ticks_per_frame_;
  ++frames_skipped_ahead_;
  return frames_ * ticks_per_frame_;
}

// Takes the blade poses of the ticks before end_tick (the newest becomes frame_pose_), waiting while the loop runs
// until it has run tick end_tick - 1 (at most max_wait_s: a loop starved that long must not hang the frames).
void RealtimeHapticCutSession::takeSamplesBefore(std::uint64_t end_tick) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                              std::chrono::duration<double>(config_.max_wait_s));
  for (;;) {
    if (!next_sample_) {
      BladeSample s;
      if (samples_->pop(s)) {
        next_sample_ = s;
      } else if (ticks_dropped_through_.load(std::memory_order_acquire) >= end_tick) {
        return;  // the frame's last pose was dropped: the loop is past it
      } else if (loop_->running() && std::chrono::steady_clock::now() < give_up) {
        std::this_thread::sleep_for(std::chrono::microseconds(100));  // about a tenth of a tick
        continue;
      } else {
        if (loop_->running()) ++frames_not_waited_for_;
        return;
      }
    }
    if (next_sample_->tick >= end_tick) return;  // the loop is past this frame (a dropped pose is skipped)
    frame_pose_ = next_sample_;
    next_sample_.reset();
    if (frame_pose_->tick + 1 >= end_tick) return;
  }
}

bool RealtimeHapticCutSession::popDecisionBefore(std::uint64_t end_tick, CutEvent& e) {
  if (!next_decision_) {
    CutEvent popped;
    if (!tool_.events().pop(popped)) return false;
    next_decision_ = popped;
  }
  if (next_decision_->tick >= end_tick) return false;
  e = *next_decision_;
  next_decision_.reset();
  return true;
}

CutFeed RealtimeHapticCutSession::applyDecisions(SimulationModel& sim) {
  if (!sim.toolSupport().cut)
    throw InputError("<real-time haptic cut session>", "model", sim.name() + " cannot be cut by a tool");
  if (last_sim_ != &sim) cut_open_ = false;  // a rebuilt model has no open stroke
  last_sim_ = &sim;
  // This frame's device time: the ticks [frames_, frames_ + 1) * ticks per frame, as in HapticCutSession.
  const std::uint64_t end_tick = skipAheadWhenLagging((++frames_) * ticks_per_frame_);
  takeSamplesBefore(end_tick);
  CutFeed feed;
  CutEvent e;
  while (popDecisionBefore(end_tick, e)) {
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
  if (cut_open_ && frame_pose_) {  // the blade at the frame's last tick extends the open stroke's swept surface
    const ToolResult r =
        sim.applyTool(bladeToolEvent(ToolPhase::Drag, frame_pose_->position_m, frame_pose_->orientation,
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
