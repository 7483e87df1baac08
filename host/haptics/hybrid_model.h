// Hybrid haptic model: local MFS at the haptic rate coupled to the global BEM at the visual rate (multi-rate).
#pragma once

#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#include <Eigen/Dense>

#include "host/haptics/bem_global.h"
#include "host/haptics/haptic_loop.h"
#include "host/haptics/mfs_local.h"
#include "host/haptics/triple_buffer.h"

namespace inc {

// What the global model hands to the haptic thread: displacements of the local model's coupled
// DOFs (local frame, metres) and when they were computed (loop time, seconds).
struct CouplingData {
  Eigen::VectorXd u_c;
  double time_s = -1.0;
  std::uint64_t global_step = 0;
};

// The local cloud sits in a frame whose z axis is the outward surface normal at the contact point
// (tissue below z = 0); its outer shell is coupled to the global model (kCoupled DOFs), the tip node
// is the tool (kPrescribed). The global model holds `contact_radius_m` of surface around the
// contact point at the tip displacement (SMW update when that element set changes).
class HybridHapticModel {
 public:
  HybridHapticModel(BemModel& global, const HemisphereCloudSpec& local_spec, const MfsMaterial& material,
                    double contact_radius_m);
  // The tool touches the surface at element `element` (contact point: its centroid). Selects the
  // global contact elements (SMW), precomputes the Somigliana rows of the coupled nodes (they move
  // only with the contact point) and resets the coupling to zero. Called from the simulation thread
  // while the haptic loop is not using the model (or before it starts).
  void touch(int element);
  const Vec3d& contactPoint() const { return contact_point_; }

  // Simulation thread, ~40 Hz: global solve with the contact held at the tip displacement (world,
  // metres); evaluates the global field at the coupled nodes and publishes it to the haptic thread.
  void globalStep(const Vec3d& tip_displacement_world, double t_s);
  // Haptic thread, 1 kHz: force on the hand (world, N) for the tip displacement, using the newest
  // published coupling; data_time_s = when it was published (for the stall fade).
  ForceResult localTick(const Vec3d& tip_displacement_world);
  // The same with the coupled boundary held at zero (the local model alone, for comparison).
  Vec3d localOnlyForce(const Vec3d& tip_displacement_world) const;

  const MfsLocalModel& local() const { return *local_; }
  const std::vector<int>& contactElements() const { return contact_elements_; }
  std::uint64_t globalSteps() const { return global_steps_.load(); }
  double lastGlobalSeconds() const { return last_global_s_; }

 private:
  Vec3d toLocal(const Vec3d& w) const;
  Vec3d toWorld(const Vec3d& l) const;
  BemModel& global_;
  HemisphereCloud cloud_;
  std::unique_ptr<MfsLocalModel> local_;
  double contact_radius_m_;
  Vec3d contact_point_, frame_[3];  // frame_: local x, y, z (= outward normal) axes in world
  std::vector<int> contact_elements_;
  std::vector<int> coupled_nodes_;   // node index of each coupled DOF triple
  Eigen::MatrixXd infl_g_, infl_h_;  // u at the coupled nodes (world) = infl_g t - infl_h u (set in touch)
  TripleBuffer<CouplingData> coupling_;
  std::atomic<std::uint64_t> global_steps_{0};
  double last_global_s_ = 0.0;
};

// Runs globalStep() on its own thread at rate_hz, reading the tool pose from the haptic loop's status.
class GlobalLoop {
 public:
  GlobalLoop(HybridHapticModel& model, HapticLoop& haptic, double rate_hz, Vec3d rest_tip_position_m);
  ~GlobalLoop();
  void start();
  void stop();
  // Period statistics of the global loop (seconds), valid after stop().
  std::vector<double> periods() const { return periods_; }

 private:
  HybridHapticModel& model_;
  HapticLoop& haptic_;
  double period_s_;
  Vec3d rest_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::vector<double> periods_;
};

}  // namespace inc
