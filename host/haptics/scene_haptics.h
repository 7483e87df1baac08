// The haptic loops a scene with models.haptics runs beside its simulation: one hand per device, the shared contact.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "host/compiled/compiled_scene.h"
#include "host/haptics/global_organ_model.h"
#include "host/haptics/haptic_hand.h"
#include "host/haptics/tip_contact.h"
#include "host/sim/simulation_model.h"

namespace inc {

// haptics.surface_point_m / surface_normal; without surface_point_m, the plane through the point of the model's
// surface (its particles when it has none) that lies farthest along the normal (the organ's top for +z).
TissuePlane sceneTissuePlane(const CompiledScene& scene, const SimulationModel& model);

// The device haptics.devices[index] names (the single device of the single-device form: index 0): a ScriptedDevice
// playing its trajectory (by time or by tick), a UdpDevice on 127.0.0.1:udp_port, or the OpenHaptics driver where
// it is built. Throws InputError(scene file, its key path, reason): no trajectory for a scripted device, a port that
// cannot be bound, a device that cannot be initialised.
std::unique_ptr<HapticDevice> makeSceneHapticDevice(const CompiledScene& scene, std::size_t index = 0);

struct SceneHapticsOptions {
  std::shared_ptr<HapticDevice> device;  // nullptr: makeSceneHapticDevice(scene, 0); else e.g. the viewer's pointer,
                                         // which then drives the first device's tool (the others keep theirs)
  HapticClock* clock = nullptr;          // nullptr: each loop's SteadyClock (a FakeClock serves one hand only)
  double record_s = 600.0;               // seconds of ticks recorded for stats() and the recorded trajectories
  bool quiet = false;                    // no progress bar (the global model's precompute)
  double max_cut_lag_s = 0.0;            // the scalpel's RealtimeCutConfig::max_lag_s: > 0 in the viewer only
};

// Built for the model the haptic tools touch. Each device is a HapticHand on its own thread at its own rate; its
// tip's elastic reaction is the MFS local model (haptics.local_*, the scene's material) condensed to a 3 x 3 tip
// stiffness: with its outer shell held (global_model "none"), or coupled to the BEM organ (global_model "bem": a
// GlobalOrganModel built here, its precompute cached; it steps once per frame in afterFrame). On a model that can be
// cut one hand may hold the scalpel (tool "scalpel", or "auto" for the first device): its CuttingTool
// (material.cutting, eqs. 15-16) decides where cuts start and stop and the model is cut between frames; every other
// hand holds a probe (contact force only). The loops' stall fade starts when the simulation's data is two frames old
// (the simulation thread late by more than a frame). Nothing runs until start(); the simulation thread calls
// beforeFrame / afterFrame around each advance() of the model.
class SceneHaptics {
 public:
  SceneHaptics(const CompiledScene& scene, const SimulationModel& model, SceneHapticsOptions options = {});
  ~SceneHaptics();
  SceneHaptics(const SceneHaptics&) = delete;
  SceneHaptics& operator=(const SceneHaptics&) = delete;

  void start();
  void stop();  // joins every loop thread; stats() and recordedTrajectory() after it
  bool running() const { return loop().running(); }
  // Simulation thread: the scalpel's cut decisions to the pipeline (cutting models; nothing otherwise).
  void beforeFrame(SimulationModel& model);
  // Simulation thread: each hand's data time and counters (HapticHand::afterFrame; the first hand's prefix is
  // "haptic", hand k's "haptic<k>"); with the global model its step and the counters
  // haptic_organ_max_displacement_m and haptic_organ_contacts.
  void afterFrame(FrameReport& report);
  // The BEM global model (global_model "bem"), else nullptr.
  const GlobalOrganModel* globalModel() const { return organ_.get(); }

  std::size_t handCount() const { return hands_.size(); }
  HapticHand& hand(std::size_t k) { return *hands_.at(k); }
  const HapticHand& hand(std::size_t k) const { return *hands_.at(k); }
  const HapticLoop& loop(std::size_t k = 0) const { return hand(k).loop(); }
  PeriodStats stats(std::size_t k = 0) const { return loop(k).stats(); }
  const HapticScheduling& scheduling(std::size_t k = 0) const { return loop(k).scheduling(); }
  Trajectory recordedTrajectory(std::size_t k = 0) const { return loop(k).recordedTrajectory(); }
  // One summary per hand ("haptic loop 1000 Hz, device scripted, ..."), then the global model's, joined by "; "
  // (after stop()).
  std::string summary() const;
  // After stop(): each hand's device trajectory (hex floats, replayable with playback "tick") and tick forces
  // (writeTickForces) in `dir`: haptic_trajectory.traj and haptic_forces.txt for the single-device form,
  // haptic_trajectory_<name>.traj and haptic_forces_<name>.txt for each listed device. Returns the files written.
  std::vector<std::string> writeRecordings(const std::string& dir) const;
  const TissuePlane& plane() const { return plane_; }
  const TipStiffness& tipStiffness() const { return tip_; }
  HapticDevice& device(std::size_t k = 0) { return hand(k).device(); }
  bool cutting() const;
  int cutDecisions() const;
  int cutsApplied() const;
  // The first hand's newest tick (sample and sent force) seen by the last afterFrame.
  const HapticStatus& newest(std::size_t k = 0) const { return hand(k).newest(); }

 private:
  TissuePlane plane_;
  TipStiffness tip_;
  std::unique_ptr<GlobalOrganModel> organ_;  // before the hands: their elastic models refer to it
  std::vector<std::unique_ptr<HapticHand>> hands_;
};

}  // namespace inc
