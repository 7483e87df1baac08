// A haptics scene's hand: device, scalpel (real-time cut session) or probe loop, frame hooks, counters, summary.
#include "host/haptics/haptic_hand.h"

#include <cstdio>

#include "model/input_error.h"

namespace inc {

HapticHand::HapticHand(std::shared_ptr<HapticDevice> device, HapticHandConfig config, HapticClock* clock)
    : device_(std::move(device)), config_(std::move(config)) {
  if (!device_) throw InputError("<haptic hand>", "device", "no device");
  if (!config_.elastic) throw InputError("<haptic hand>", "elastic", "no elastic force model");
  if (config_.scalpel) {
    cut_tool_ =
        std::make_unique<CuttingTool>(config_.elastic, config_.cut, config_.plane.point_m, config_.plane.normal);
    RealtimeCutConfig rc;
    rc.blade_length_m = config_.blade_length_m;
    rc.blade_axis_device = config_.blade_axis_device;
    rc.frame_dt_s = config_.frame_dt_s;
    rc.max_lag_s = config_.max_cut_lag_s;
    rc.loop = config_.loop;
    cut_session_ = std::make_unique<RealtimeHapticCutSession>(*device_, *cut_tool_, rc, clock);
  } else {
    probe_ = std::make_unique<ProbeTool>(config_.elastic, config_.plane.point_m, config_.plane.normal);
    probe_loop_ = std::make_unique<HapticLoop>(
        *device_, [this](const ForceRequest& q) { return probe_link_.stamp(probe_->tick(q), q.t_s); }, config_.loop,
        clock);
  }
}

HapticHand::~HapticHand() { stop(); }

const HapticLoop& HapticHand::loop() const { return cut_session_ ? cut_session_->loop() : *probe_loop_; }

void HapticHand::start() {
  if (cut_session_) {
    cut_session_->start();
  } else {
    probe_link_.setDataTime(0.0);  // a first frame that never ends fades the force like any later stall
    probe_loop_->start();
  }
}

void HapticHand::stop() {
  if (cut_session_)
    cut_session_->stop();
  else if (probe_loop_)
    probe_loop_->stop();
}

void HapticHand::beforeFrame(SimulationModel& model) {
  if (cut_session_) cut_session_->applyDecisions(model);
}

void HapticHand::afterFrame(FrameReport& report) {
  const HapticWindow w = cut_session_ ? cut_session_->frameDone() : probe_link_.frameDone();
  if (cut_session_) {
    newest_ = cut_session_->newestStatus();
  } else {
    probe_loop_->status().update();
    newest_ = probe_loop_->status().front();
  }
  const std::string& p = config_.counter_prefix;
  report.counters[p + "_hz"] = w.rate_hz;
  report.counters[p + "_p50_ms"] = w.p50_ms;
  report.counters[p + "_p99_ms"] = w.p99_ms;
  report.counters[p + "_max_ms"] = w.max_ms;
  report.counters[p + "_missed"] = double(newest_.missed);
  report.counters[p + "_force_n"] = norm(newest_.force_n);
  if (cut_session_) report.counters[p + "_cut_decisions"] = cut_session_->decisions();
}

std::string HapticHand::summary() const {
  const PeriodStats s = loop().stats();
  char buf[512];
  std::snprintf(
      buf, sizeof buf,
      "haptic loop %s%.0f Hz, device %s, tool %s, %s: %llu ticks, period p50 %.3f ms, p99 %.3f ms, max %.3f "
      "ms, missed %llu, skipped %llu, compute p99 %.1f us",
      config_.name.empty() ? "" : (config_.name + " ").c_str(), 1.0 / loop().period_s(), device_->name().c_str(),
      cut_session_ ? "scalpel" : "probe", loop().scheduling().realtime ? "SCHED_FIFO" : "normal scheduling",
      static_cast<unsigned long long>(s.ticks), 1e3 * s.p50_s, 1e3 * s.p99_s, 1e3 * s.max_s,
      static_cast<unsigned long long>(s.missed), static_cast<unsigned long long>(s.skipped), 1e6 * s.compute_p99_s);
  std::string out = buf;
  if (cut_session_)
    out += ", cut decisions " + std::to_string(cut_session_->decisions()) + ", cuts applied " +
           std::to_string(cut_session_->cutsApplied());
  return out;
}

}  // namespace inc
