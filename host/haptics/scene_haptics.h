// The haptic loop a scene with models.haptics runs beside its simulation: device, tip contact, cutting, statistics.
#pragma once

#include <memory>
#include <string>

#include "host/haptics/cutting_tool.h"
#include "host/haptics/haptic_cut_realtime.h"
#include "host/haptics/haptic_link.h"
#include "host/haptics/haptic_loop.h"
#include "host/haptics/tip_contact.h"
#include "host/scene.h"
#include "host/simulation_model.h"

namespace inc {

// The tissue surface the tool's contact model presses into: a plane (docs/haptics.md, CuttingTool).
struct TissuePlane {
  Vec3d point_m;
  Vec3d normal{0, 0, 1};  // outward, unit
};
// haptics.surface_point_m / surface_normal; without surface_point_m, the plane through the point of the model's
// surface (its particles when it has none) that lies farthest along the normal (the organ's top for +z).
TissuePlane sceneTissuePlane(const Scene& scene, const SimulationModel& model);

// The device haptics.device names: a ScriptedDevice playing haptics.trajectory (by time or by tick), a UdpDevice
// on 127.0.0.1:haptics.udp_port, or the OpenHaptics driver where it is built. Throws InputError(scene file,
// "haptics.<key>", reason): no trajectory for a scripted device, a port that cannot be bound, a device that
// cannot be initialised.
std::unique_ptr<HapticDevice> makeSceneHapticDevice(const Scene& scene);

struct SceneHapticsOptions {
  std::shared_ptr<HapticDevice> device;  // nullptr: makeSceneHapticDevice(scene); else e.g. the viewer's pointer
  HapticClock* clock = nullptr;          // nullptr: the loop's SteadyClock
  double record_s = 600.0;               // seconds of ticks recorded for stats() and the recorded trajectory
};

// Built for the model the haptic tool touches. The tip's elastic reaction is the MFS local model (haptics.local_*,
// the scene's material) condensed to a 3 x 3 tip stiffness; on a model that can be cut (a dissection scene) the
// CuttingTool (material.cutting, eqs. 15-16) runs in a RealtimeHapticCutSession, whose decisions go to the model's
// cutting pipeline between frames; on any other model a ProbeTool. The loop's stall fade starts when the
// simulation's data is two frames old (the simulation thread late by more than a frame). Nothing runs until
// start(); the simulation thread calls beforeFrame / afterFrame around each advance() of the model.
class SceneHaptics {
 public:
  SceneHaptics(const Scene& scene, const SimulationModel& model, SceneHapticsOptions options = {});
  ~SceneHaptics();
  SceneHaptics(const SceneHaptics&) = delete;
  SceneHaptics& operator=(const SceneHaptics&) = delete;

  void start();
  void stop();  // joins the loop thread; stats() and recordedTrajectory() after it
  bool running() const { return loop().running(); }
  // Simulation thread: cut decisions to the pipeline (cutting models; nothing otherwise).
  void beforeFrame(SimulationModel& model);
  // Simulation thread: data time for the stall fade; counters haptic_hz, haptic_p99_ms (and haptic_cut_decisions).
  void afterFrame(FrameReport& report);

  const HapticLoop& loop() const;
  PeriodStats stats() const { return loop().stats(); }
  const HapticScheduling& scheduling() const { return loop().scheduling(); }
  Trajectory recordedTrajectory() const { return loop().recordedTrajectory(); }
  // "haptic loop: 1000 Hz <device>, N ticks, period p50 .. p99 .. max .. ms, missed M, ..." (after stop()).
  std::string summary() const;
  const TissuePlane& plane() const { return plane_; }
  const TipStiffness& tipStiffness() const { return tip_; }
  HapticDevice& device() { return *device_; }
  bool cutting() const { return bool(cut_session_); }
  int cutDecisions() const { return cut_session_ ? cut_session_->decisions() : 0; }
  int cutsApplied() const { return cut_session_ ? cut_session_->cutsApplied() : 0; }
  // The newest tick (sample and sent force) seen by the last afterFrame.
  const HapticStatus& newest() const { return newest_; }

 private:
  std::shared_ptr<HapticDevice> device_;
  TissuePlane plane_;
  TipStiffness tip_;
  std::unique_ptr<CuttingTool> cut_tool_;
  std::unique_ptr<RealtimeHapticCutSession> cut_session_;
  std::unique_ptr<ProbeTool> probe_;
  HapticLink probe_link_;
  std::unique_ptr<HapticLoop> probe_loop_;
  HapticStatus newest_;
};

}  // namespace inc
