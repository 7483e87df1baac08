// Real-time haptic cutting session: cut decisions at 1 kHz on the haptic thread, the model cut between its frames.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "host/haptics/cutting_tool.h"
#include "host/haptics/haptic_link.h"
#include "host/haptics/haptic_loop.h"
#include "host/haptics/spsc_ring.h"
#include "host/sim/simulation_model.h"

namespace inc {

struct RealtimeCutConfig {
  double blade_length_m = 0.05;      // the blade: a segment of this length centred on the device's tip
  Vec3d blade_axis_device{0, 0, 1};  // its direction in the device frame (turned by the sample's orientation)
  double frame_dt_s = 0.02;          // the simulation frame: ticks per frame = round(frame_dt_s * loop.rate_hz)
  double max_wait_s = 1.0;           // longest a frame waits for the loop to reach the frame's last tick
  // > 0 (interactive use): a frame whose device time lags the loop's newest tick by more than this skips ahead to
  // it, so that the cut keeps up with the hand (the frames' ticks then depend on timing again); 0: never skips.
  double max_lag_s = 0.0;
  HapticLoopConfig loop;
};

// The blade's pose at one haptic tick, as the loop hands it to the simulation thread.
struct BladeSample {
  std::uint64_t tick = 0;
  Vec3d position_m;
  double orientation[4] = {1.0, 0.0, 0.0, 0.0};  // w, x, y, z
};

// What applyDecisions() handed to the cutting pipeline.
struct CutFeed {
  int events = 0;            // start/stop decisions applied
  bool cut_applied = false;  // a stop decision's Release applied a cut
};

// The threaded counterpart of HapticCutSession: start() runs the loop on its own thread (HapticLoop::start:
// SCHED_FIFO where permitted), each tick the cutting tool (eqs. 15-16) decides on that tick's device sample and
// pushes its decisions to a lock-free queue, and the loop pushes the tick's blade pose to a second one. The
// simulation thread, between frames, calls applyDecisions(): frame n takes the ticks of its device time,
// [n, n + 1) * ticks-per-frame, whatever wall time they arrived at: it waits (polling, at most max_wait_s) until the
// loop has run the frame's last tick, applies the decisions of those ticks in tick order (start ->
// ToolPhase::Press, stop -> Release, which applies the cut), then, while a cut is open, a Drag with the pose of
// the frame's last tick; later ticks stay queued for later frames. That is what the lockstep HapticCutSession
// does, so the model sees the same tool events on every run and the topology depends on the device trajectory
// alone, not on thread timing (a scalpel stroke through the organ gives two pieces every time), and the lockstep
// session replaying the recorded trajectory (loop().recordedTrajectory()) reproduces it bit for bit. The loop
// never waits for the simulation: a full queue drops (and counts) what does not fit. Then the model advances and
// frameDone() publishes the data time (stall fade) and returns the window statistics; runFrame() does the three.
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
  // The newest tick's sample and force (simulation thread: the loop's status triple buffer).
  const HapticStatus& newestStatus();
  int decisions() const { return decisions_; }
  int cutsApplied() const { return cuts_applied_; }
  const std::vector<std::string>& messages() const { return messages_; }
  // Blade poses the loop could not queue (the simulation more than the queue's 8 s behind), and frames that gave up
  // waiting for their last tick (max_wait_s): both 0 unless the timing reached the tool events.
  std::uint64_t droppedSamples() const { return dropped_samples_.load(std::memory_order_relaxed); }
  int framesNotWaitedFor() const { return frames_not_waited_for_; }
  int framesSkippedAhead() const { return frames_skipped_ahead_; }  // max_lag_s catch-ups

 private:
  using SampleQueue = SpscRing<BladeSample, 8192>;
  std::uint64_t skipAheadWhenLagging(std::uint64_t end_tick);
  void takeSamplesBefore(std::uint64_t end_tick);
  bool popDecisionBefore(std::uint64_t end_tick, CutEvent& e);
  CuttingTool& tool_;
  RealtimeCutConfig config_;
  HapticLink link_;
  std::unique_ptr<SampleQueue> samples_;  // the loop's blade poses, one per tick (heap: 512 KiB)
  std::atomic<std::uint64_t> dropped_samples_{0}, ticks_dropped_through_{0};  // the newest dropped tick + 1
  std::unique_ptr<HapticLoop> loop_;
  std::uint64_t ticks_per_frame_ = 1, frames_ = 0;
  std::optional<BladeSample> frame_pose_, next_sample_;  // the newest pose taken; one popped for a later frame
  std::optional<CutEvent> next_decision_;                // a decision popped for a later frame
  bool cut_open_ = false;
  const SimulationModel* last_sim_ = nullptr;
  int decisions_ = 0, cuts_applied_ = 0, frames_not_waited_for_ = 0, frames_skipped_ahead_ = 0;
  std::vector<std::string> messages_;
};

}  // namespace inc
