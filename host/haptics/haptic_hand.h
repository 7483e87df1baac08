// One hand of a haptics scene: its device, its tool (scalpel or probe) in its own 1 kHz loop, and the frame hooks.
#pragma once

#include <memory>
#include <string>

#include "host/haptics/cutting_tool.h"
#include "host/haptics/haptic_cut_realtime.h"
#include "host/haptics/haptic_link.h"
#include "host/haptics/haptic_loop.h"
#include "host/haptics/tip_contact.h"
#include "host/sim/simulation_model.h"

namespace inc {

// The tissue surface the tools' contact model presses into: a plane (docs/haptics.md, CuttingTool).
struct TissuePlane {
  Vec3d point_m;
  Vec3d normal{0, 0, 1};  // outward, unit
};

struct HapticHandConfig {
  std::string name;                       // "" for the single device of a scene, else its haptics.devices[i].name
  std::string counter_prefix = "haptic";  // model counters <prefix>_hz, <prefix>_p99_ms, ...
  bool scalpel = false;                   // a CuttingTool whose decisions cut the model; false: a ProbeTool
  TissuePlane plane;
  CuttingTool::Elastic elastic;      // the tissue's elastic reaction (tipElastic, or a global model's contact)
  CutThresholds<double> cut;         // scalpel: eqs. 15-16 thresholds (material.cutting)
  double blade_length_m = 0.05;      // scalpel
  Vec3d blade_axis_device{0, 0, 1};  // scalpel
  double frame_dt_s = 0.02;          // scalpel: the simulation frame its cut decisions are grouped by (device time)
  double max_cut_lag_s = 0.0;        // scalpel: RealtimeCutConfig::max_lag_s (0: the cut never skips ahead)
  HapticLoopConfig loop;
};

// A scalpel runs its CuttingTool in a RealtimeHapticCutSession (decisions handed to the model between frames); a
// probe runs its ProbeTool in a HapticLoop with its own HapticLink. Each hand has its own loop thread, rate, link
// and statistics; hands share nothing on the hot path. Nothing runs until start().
class HapticHand {
 public:
  // clock == nullptr: the loop's SteadyClock. Throws InputError for a bad config.
  HapticHand(std::shared_ptr<HapticDevice> device, HapticHandConfig config, HapticClock* clock = nullptr);
  ~HapticHand();
  HapticHand(const HapticHand&) = delete;
  HapticHand& operator=(const HapticHand&) = delete;

  void start();
  void stop();  // joins the loop thread; records, stats() and recordedTrajectory() after it
  // Simulation thread, before the model's frame: a scalpel's cut decisions to the model's cutting pipeline.
  void beforeFrame(SimulationModel& model);
  // Simulation thread, after the frame: the data time for the stall fade and the counters <prefix>_hz, _p50_ms,
  // _p99_ms, _max_ms (over the newest 1000 periods), _missed (since the start), _force_n (the newest force sent
  // to the hand), and for a scalpel _cut_decisions.
  void afterFrame(FrameReport& report);

  const std::string& name() const { return config_.name; }
  bool scalpel() const { return bool(cut_session_); }
  const HapticLoop& loop() const;
  HapticDevice& device() { return *device_; }
  const HapticDevice& device() const { return *device_; }
  int cutDecisions() const { return cut_session_ ? cut_session_->decisions() : 0; }
  int cutsApplied() const { return cut_session_ ? cut_session_->cutsApplied() : 0; }
  // The newest tick (sample and sent force) seen by the last afterFrame.
  const HapticStatus& newest() const { return newest_; }
  // "haptic loop [<name> ]1000 Hz, device scripted, tool probe, SCHED_FIFO: N ticks, period p50 .. p99 .. max ..
  // ms, missed M, ..." (after stop()).
  std::string summary() const;

 private:
  std::shared_ptr<HapticDevice> device_;
  HapticHandConfig config_;
  std::unique_ptr<CuttingTool> cut_tool_;
  std::unique_ptr<RealtimeHapticCutSession> cut_session_;
  std::unique_ptr<ProbeTool> probe_;
  HapticLink probe_link_;
  std::unique_ptr<HapticLoop> probe_loop_;
  HapticStatus newest_;
};

}  // namespace inc
