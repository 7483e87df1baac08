// Real-time haptic cutting session: cut decisions at 1 kHz on the haptic thread, the model cut between its frames.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "host/haptics/cutting_tool.h"
#include "host/haptics/haptic_link.h"
#include "host/haptics/haptic_loop.h"
#include "host/sim/simulation_model.h"

namespace inc {

struct RealtimeCutConfig {
  double blade_length_m = 0.05;      // the blade: a segment of this length centred on the device's tip
  Vec3d blade_axis_device{0, 0, 1};  // its direction in the device frame (turned by the sample's orientation)
  HapticLoopConfig loop;
};

// What applyDecisions() handed to the cutting pipeline.
struct CutFeed {
  int events = 0;            // start/stop decisions applied
  bool cut_applied = false;  // a stop decision's Release applied a cut
};

// The threaded counterpart of HapticCutSession (which stays for replays and tests): start() runs the loop on its
// own thread (HapticLoop::start: SCHED_FIFO where permitted), each tick the cutting tool (eqs. 15-16) decides on
// the newest device sample and pushes its decisions to a lock-free queue. The simulation thread, between
// frames, calls applyDecisions(): the decisions since the last call, in tick order (start -> ToolPhase::Press,
// stop -> Release, which applies the cut), then a Drag with the newest pose (the loop's status triple buffer)
// while a cut is open; then it advances the model and calls frameDone() (data time for the stall fade, window
// statistics for the counters). runFrame() does the three. Nothing on the hot path takes a lock. Which frame
// sees a decision depends on timing: a bit-exact replay of such a session replays its recorded trajectory
// (loop().recordedTrajectory()) through the lockstep HapticCutSession.
class RealtimeHapticCutSession {
 public:
  // clock == nullptr: the loop's SteadyClock. Throws InputError for a bad config.
  RealtimeHapticCutSession(HapticDevice& device, CuttingTool& tool, const RealtimeCutConfig& config,
                           HapticClock* clock = nullptr);
  ~RealtimeHapticCutSession();
  RealtimeHapticCutSession(const RealtimeHapticCutSession&) = delete;
  RealtimeHapticCutSession& operator=(const RealtimeHapticCutSession&) = delete;

  void start();
  void stop();  // joins the loop thread; records and stats() are read after it
  // Simulation thread. Throws InputError when `sim` cannot be cut by a tool.
  CutFeed applyDecisions(SimulationModel& sim);
  HapticWindow frameDone() { return link_.frameDone(); }
  // applyDecisions, advance(frame_dt_s), frameDone; adds the counters haptic_hz, haptic_p99_ms and
  // haptic_cut_decisions to the report.
  FrameReport runFrame(SimulationModel& sim, double frame_dt_s);

  HapticLoop& loop() { return *loop_; }
  const HapticLoop& loop() const { return *loop_; }
  // The newest tick's sample and force (simulation thread; updated by applyDecisions / newestStatus).
  const HapticStatus& newestStatus();
  int decisions() const { return decisions_; }
  int cutsApplied() const { return cuts_applied_; }
  const std::vector<std::string>& messages() const { return messages_; }

 private:
  CuttingTool& tool_;
  RealtimeCutConfig config_;
  HapticLink link_;
  std::unique_ptr<HapticLoop> loop_;
  bool cut_open_ = false;
  const SimulationModel* last_sim_ = nullptr;
  int decisions_ = 0, cuts_applied_ = 0;
  std::vector<std::string> messages_;
};

}  // namespace inc
