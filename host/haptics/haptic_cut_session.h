// A haptic cutting session in lockstep: haptic ticks, the cutting tool's decisions and simulation frames, replayable.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "host/haptics/cutting_tool.h"
#include "host/haptics/haptic_loop.h"
#include "host/sim/simulation_model.h"

namespace inc {

struct HapticCutSessionConfig {
  double frame_dt_s = 0.02;          // simulation frame; ticks per frame = round(frame_dt_s * loop.rate_hz)
  double blade_length_m = 0.05;      // the blade: a segment of this length centred on the device's tip
  Vec3d blade_axis_device{0, 0, 1};  // its direction in the device frame (turned by the sample's orientation)
  HapticLoopConfig loop;
};

// What the topology of the simulated organ is after a frame: what a replay must reproduce exactly.
struct TopologySummary {
  std::size_t particles = 0;  // spheres of a metaball organ
  std::size_t links = 0;      // the model's "links" counter (sphere links), 0 when it has none
  std::size_t surface_triangles = 0;
  int cuts_applied = 0;
  std::uint64_t position_hash = 0;  // FNV-1a of the bytes of every particle and surface vertex position
  bool operator==(const TopologySummary& o) const {
    return particles == o.particles && links == o.links && surface_triangles == o.surface_triangles &&
           cuts_applied == o.cuts_applied && position_hash == o.position_hash;
  }
};
TopologySummary summarizeTopology(const SimulationModel& sim, const FrameReport& report);

// The blade of a cut decision as a tool event for the cutting pipeline: a segment of blade_length_m centred on
// `tip` along blade_axis_device (unit) turned by the device orientation (w, x, y, z). Lockstep and real-time
// sessions build their events with it.
ToolEvent bladeToolEvent(ToolPhase phase, const Vec3d& tip, const double orientation[4], const Vec3d& blade_axis_device,
                         double blade_length_m);

struct SessionFrame {
  std::uint64_t ticks_done = 0;  // haptic ticks run before this frame advanced
  int cut_events = 0;            // start/stop decisions handed to the cutting pipeline in this frame
  bool cut_applied = false;
  TopologySummary topology;  // after the frame
};

// Deterministic interleaving (tests, replays, offline regression runs of interactive behaviour): each
// frame runs ticks-per-frame haptic ticks on the calling thread (clock: a FakeClock, so no real waiting),
// then hands the cutting tool's decisions of those ticks to the model's cutting pipeline in tick order
// (start -> ToolPhase::Press, stop -> Release, which applies the cut), a Drag with the newest blade pose
// while a cut is open, and advances the model one frame. The haptic forces depend only on the device
// samples, the topology only on the decisions and poses, so replaying the recorded device trajectory
// (HapticLoop::recordedTrajectory, ScriptedDevice kByTick) reproduces forces and topology bit for bit on
// the same backend. The real-time session (haptic_cut_realtime.h) runs the loop on its own thread instead and
// consumes tool.events() between frames the same way.
class HapticCutSession {
 public:
  // Throws InputError when the model cannot cut (toolSupport().cut) or the config is bad.
  HapticCutSession(SimulationModel& sim, HapticDevice& device, CuttingTool& tool, const HapticCutSessionConfig& config);
  void runFrames(int frames);
  const HapticLoop& loop() const { return *loop_; }
  const std::vector<SessionFrame>& frames() const { return frames_; }
  int ticksPerFrame() const { return ticks_per_frame_; }
  // Messages of refused tool events (none expected).
  const std::vector<std::string>& messages() const { return messages_; }

 private:
  ToolEvent bladeEvent(ToolPhase phase, const Vec3d& tip, const double orientation[4]) const;
  SimulationModel& sim_;
  CuttingTool& tool_;
  HapticCutSessionConfig config_;
  FakeClock clock_;
  std::unique_ptr<HapticLoop> loop_;
  int ticks_per_frame_ = 1;
  bool cut_open_ = false;
  std::vector<SessionFrame> frames_;
  std::vector<std::string> messages_;
};

}  // namespace inc
