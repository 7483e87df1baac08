// Hybrid haptic model: local MFS around the tool at the haptic rate, coupled to the global BEM organ (multi-rate).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include <Eigen/Dense>

#include "host/haptics/bem_global.h"
#include "host/haptics/haptic_loop.h"
#include "host/haptics/mfs_local.h"
#include "host/haptics/triple_buffer.h"

namespace inc {

// What the simulation side publishes for the haptic thread (one triple-buffer slot, always written whole).
struct HybridCoupling {
  bool touching = false;
  Vec3d contact_point;                                      // world, m
  Vec3d frame[3];                                           // local x, y, z (= outward normal) axes in world
  Eigen::Matrix3d tip_stiffness = Eigen::Matrix3d::Zero();  // N/m, local frame: F = K d (tip tools only)
  double time_s = -1.0;  // loop time of the newest global step (stall fade); < 0: none yet
  std::uint64_t global_step = 0;
};

// The local MFS cloud sits in a frame whose z axis is the outward surface normal at the contact point
// (tissue below z = 0). Its prescribed DOFs (role kPrescribed) are the tool, its coupled DOFs (kCoupled,
// the outer shell) follow the global model. Coupling (see docs/haptics.md, "Hybrid coupling"): the
// tool loads the organ with the force F it applies, F = P f_a (P sums the prescribed DOFs' reactions per
// direction). The organ's displacement at the coupled nodes is u_c = C F, C = Boussinesq-Cerruti
// half-space field of a point force (physics/boussinesq.h: the near field no element-sized BEM can
// resolve) + the regular remainder from the BEM (finite organ, curvature, supports: 3 solves with the
// precomputed inverse per contact point, uniform over the small local region). With eq. 6,
// f_a = S_aa u_a + S_ac u_c, this closes to F = (I - P S_ac C)^-1 P S_aa u_a: exact for the linear models,
// a 3 x n_a product per haptic tick (3 x 3 for a tip tool), no lag behind the global thread.
class HybridHapticModel {
 public:
  // Tip tool: the cloud's tip node (singular weight, eq. 5) is prescribed in x, y, z; the outer shell is
  // coupled. Throws InputError for a bad spec.
  HybridHapticModel(BemModel& global, const HemisphereCloudSpec& local_spec, const Material& material);
  // Any local tool: a local model whose roles are set (e.g. a flat punch: the z DOFs of the face nodes
  // prescribed), shared between organs and contacts (its K_bb factorisation does not depend on them).
  // Coupled DOFs must keep away from the contact point (more than a quarter of the cloud's radius).
  HybridHapticModel(BemModel& global, std::shared_ptr<const MfsLocalModel> local);

  // The tool touches the surface at the centroid of element `element` (its plane is the local z = 0).
  // Computes C and the condensed tool operator and publishes them (SMW-free: the contact is a load, no
  // boundary condition changes). Call from the thread that runs globalStep() (one producer). Throws
  // InputError for an out-of-range element or one held by a displacement condition.
  void touch(int element);
  // No contact: the published tool force is zero.
  void release();
  const Vec3d& contactPoint() const { return contact_point_; }
  int contactElement() const { return contact_element_; }
  const Vec3d& contactNormal() const { return frame_[2]; }

  // Force the tool applies to the organ (local frame, N) for the prescribed DOF values u_a (local, m),
  // with the global model's response included. Simulation-side (uses the producer's copy).
  Eigen::Vector3d toolForceLocal(const Eigen::VectorXd& u_a) const;
  // The same with the coupled DOFs held at zero (the local model alone, the paper's MFS of [10]).
  Eigen::Vector3d localOnlyForceLocal(const Eigen::VectorXd& u_a) const;
  // Tip tools, world frame: force on the hand (= minus the force on the organ) for a tip displacement.
  Vec3d localOnlyForce(const Vec3d& tip_displacement_world) const;

  // Simulation thread, ~40 Hz (tip tools): the global model for the newest tip displacement (world, m):
  // the tool force, the coupled-node displacements (the local field's boundary) and the organ surface
  // displacement per element (display); publishes the step time for the haptic thread's stall fade.
  void globalStep(const Vec3d& tip_displacement_world, double t_s);
  // Haptic thread, 1 kHz (tip tools): force on the hand (world, N) from the newest published coupling;
  // data_time_s = time of the newest global step.
  ForceResult localTick(const Vec3d& tip_displacement_world);

  // Tip tools, for the current contact, in the world frame: the force on the organ per tip displacement (3 x 3,
  // N/m: the published tip stiffness) and the organ's surface displacement per unit force on the organ (3E x 3,
  // m/N; at the contact element itself the half-space field is singular: globalStep puts the tip's displacement
  // there instead).
  Eigen::Matrix3d worldToolStiffness() const;
  Eigen::MatrixXd worldSurfaceCompliance() const;
  // The local model alone (coupled DOFs held) at element `element`'s contact frame, world: force on the organ
  // per tip displacement (N/m). Tip tools; any element, also a held one.
  Eigen::Matrix3d worldLocalOnlyStiffness(int element) const;

  const MfsLocalModel& local() const { return *local_; }
  std::uint64_t globalSteps() const { return global_steps_.load(); }
  double lastGlobalSeconds() const { return last_global_s_; }
  double lastTouchSeconds() const { return last_touch_s_; }
  // The interface compliance C (n_c x 3, local frame, m/N) and its regular (BEM) part R (3 x 3) of the
  // current contact; the coupled-node displacements and the surface displacement (3 per element,
  // world) of the last global step.
  const Eigen::MatrixXd& interfaceCompliance() const { return c_; }
  const Eigen::Matrix3d& regularCompliance() const { return r_; }
  const Eigen::VectorXd& lastCoupledDisplacement() const { return u_c_; }
  const Eigen::VectorXd& lastSurfaceDisplacement() const { return surface_u_; }
  // Spectral radius of P S_ac C: a staggered (Dirichlet-Neumann) exchange between the two models would
  // converge only below 1; the condensed coupling needs no iteration.
  double staggeredIterationFactor() const;

 private:
  void setUp();
  Vec3d toLocal(const Vec3d& w) const { return {dot(w, frame_[0]), dot(w, frame_[1]), dot(w, frame_[2])}; }
  Vec3d toWorld(const Vec3d& l) const { return frame_[0] * l.x + frame_[1] * l.y + frame_[2] * l.z; }
  BemModel& global_;
  std::shared_ptr<const MfsLocalModel> local_;
  Eigen::MatrixXd p_;             // 3 x n_a: direction of each prescribed DOF
  std::vector<Vec3d> coupled_x_;  // local position of each coupled DOF's node
  std::vector<int> coupled_dir_;  // and its direction (0, 1, 2)
  bool tip_tool_ = false;
  // Producer-side state (the thread that calls touch / globalStep).
  bool touching_ = false;
  int contact_element_ = -1;
  Vec3d contact_point_, frame_[3];
  Eigen::MatrixXd c_;  // n_c x 3
  Eigen::Matrix3d r_ = Eigen::Matrix3d::Zero();
  Eigen::MatrixXd tool_op_;                // 3 x n_a: (I - P S_ac C)^-1 P S_aa
  Eigen::MatrixXd surface_b_, surface_r_;  // 3E x 3 (world, per unit local force): singular and regular parts
  Eigen::VectorXd u_c_, surface_u_;
  HybridCoupling published_;
  TripleBuffer<HybridCoupling> coupling_;
  std::atomic<std::uint64_t> global_steps_{0};
  double last_global_s_ = 0.0, last_touch_s_ = 0.0;
};

// The contact frame at a surface point with outward unit normal n: frame[0], frame[1] tangent, frame[2] = n.
void contactFrame(const Vec3d& n, Vec3d frame[3]);

// Runs globalStep() on its own thread at rate_hz, reading the tool pose from the haptic loop's status.
// The thread runs at a lower CPU priority than normal (nice +5 where permitted): its work can wait a few
// milliseconds, the haptic tick cannot.
class GlobalLoop {
 public:
  GlobalLoop(HybridHapticModel& model, HapticLoop& haptic, double rate_hz, Vec3d rest_tip_position_m);
  ~GlobalLoop();
  // Benchmark load: touch() the current contact element again before every step, as a contact that moves
  // to a new element every visual frame would (3 BEM solves and the half-space data per step).
  void setRetouchEachStep(bool on) { retouch_ = on; }
  void start();
  void stop();
  // Period statistics of the global loop (seconds), valid after stop().
  std::vector<double> periods() const { return periods_; }
  // Seconds of work (touch + step) of each step, valid after stop().
  std::vector<double> workSeconds() const { return work_; }

 private:
  bool retouch_ = false;
  std::vector<double> work_;
  HybridHapticModel& model_;
  HapticLoop& haptic_;
  double period_s_;
  Vec3d rest_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::vector<double> periods_;
};

}  // namespace inc
