// The MLS solver on the CPU: the passes of physics/mls_passes.h looped over a thread team, with rest pair tables.
#pragma once

#include <memory>

#include "base/team.h"
#include "model/mls_model.h"
#include "model/mls_solver.h"
#include "physics/cut_coupling.h"

namespace inc::cpu {

template <typename T>
class MlsCpuSolver final : public MlsSolver {
 public:
  explicit MlsCpuSolver(MlsModel<T> model);

  BackendKind backend() const override { return BackendKind::Cpu; }
  Precision precision() const override { return sizeof(T) == 8 ? Precision::Float64 : Precision::Float32; }
  std::size_t size() const override { return model_.size(); }
  const MlsModelStats& modelStats() const override { return model_.stats; }
  Vec3d origin() const override { return model_.origin; }
  std::vector<Vec3d> restPositions() const override;

  MlsFrameStats advance(double frame_dt, int fixed_substeps = 0) override;
  void step(double dt, int n) override;
  void computeForces() override;
  MlsReduction reduce() override;

  void setDisplacements(const std::vector<Vec3d>& u) override;
  void setVelocities(const std::vector<Vec3d>& v) override;
  void displacements(std::vector<Vec3d>& out) const override;
  void velocities(std::vector<Vec3d>& out) const override;
  void forces(std::vector<Vec3d>& out) const override;
  void energies(std::vector<double>& out) const override;
  void setPrescribed(const std::vector<std::int32_t>& particles, const std::vector<Vec3d>& targets) override;
  void release(const std::vector<std::int32_t>& particles) override;
  void setCouplingGroups(const MlsCouplingGroups& groups) override;
  void setCouplingAnchors(const std::vector<Vec3d>& anchors) override;
  void couplingDisplacements(std::vector<Vec3d>& out) override;
  void saveCheckpoint() override;
  void restoreCheckpoint() override;
  MemoryReport memory() const override;

  const MlsModel<T>& model() const { return model_; }
  const MlsState<T>& state() const { return state_; }

 private:
  // Runs n substeps of dt; stage times (ms) are added to `stats` when given.
  void substeps(T dt, int n, MlsFrameStats* stats);
  MlsView<T> view();  // the passes' view, with the coupling arrays when groups are set
  CouplingView<T> couplingView();
  void couplingPass();      // eqs. 11-13 for every group at the current displacement
  void buildPairTables();   // pair_gradient_, pair_force_, weighted_sum_ from the model (once)
  int teamThreads() const;  // threads worth a team for this many particles
  MlsModel<T> model_;
  MlsState<T> state_;
  // Rest pair tables (MlsView::pair_gradient, pair_force per CSR slot, weighted_sum per particle).
  std::vector<Vec3<T>> pair_gradient_, pair_force_, weighted_sum_;
  // Outputs of the last stress / force passes: each particle's stiffening factor and elastic force.
  std::vector<T> stiffening_out_;
  std::vector<Vec3<T>> elastic_force_;
  TeamRunner team_;
  // Coupling groups in precision T, positions relative to the model origin (empty: no coupling).
  std::vector<std::int32_t> cg_member_offsets_{0}, cg_members_, cg_spring_offsets_{0}, particle_group_;
  std::vector<Vec3<T>> cg_rest_centre_, cg_anchor_, cg_displacement_, cg_force_;
  std::vector<T> cg_rest_length_, cg_stiffness_;
  std::vector<Vec3<T>> cg_centroid_;  // rotation-aware eq. 13: rest frames (physics/cut_coupling.h)
  std::vector<Mat3<T>> cg_gram_, cg_inertia_inverse_, cg_torque_;
  std::vector<pbd::Quat<T>> cg_rotation_, saved_rotation_;
  std::vector<Vec3<T>> saved_u_, saved_v_;
  // forces_valid_: force, elastic_force_, stress moments, energies and stiffening_out_ belong to the current
  // displacement and anchors. coupling_stale_: only the anchors changed since (the elastic part is still valid).
  bool forces_valid_ = false;
  bool coupling_stale_ = false;
  MlsBladeContact<T> blade_t_;      // the blade of the substeps running now (MlsView::blade when bladeOn())
  MlsStaticContacts<T> statics_t_;  // the static colliders relative to the origin (MlsView::statics when staticsOn())
};

std::unique_ptr<MlsSolver> makeMlsSolverCpu(MlsModel<float> model);
std::unique_ptr<MlsSolver> makeMlsSolverCpu(MlsModel<double> model);

}  // namespace inc::cpu
