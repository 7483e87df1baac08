// The backend-agnostic MLS elasticity solver interface (CPU and CUDA implementations) and its factory.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "model/backend.h"
#include "model/input_error.h"
#include "model/mls_model.h"
#include "model/stage_timing.h"
#include "physics/mls_blade_contact.h"
#include "physics/mls_static_contact.h"
#include "physics/vec3.h"

namespace inc {

// Once-per-frame reductions (device reductions on the GPU; one small download).
struct MlsReduction {
  double kinetic_energy = 0.0;    // J, 1/2 sum m v^2
  double elastic_energy = 0.0;    // J, sum v_i psi_i (eq. 8, with the volume penalty)
  double potential_energy = 0.0;  // J, -sum m g . u (gravity, relative to rest)
  double max_displacement = 0.0;  // m
  double stiffening = 1.0;        // largest mlsStiffening (>= 1): the stable step is divided by its sqrt
  bool finite = true;
  std::int64_t first_bad = -1;  // lowest index with a non-finite u, v, f or energy
  std::string bad_stage;        // "integrate" (u, v), "forces" (f) or "stress" (energy)
  double total() const { return kinetic_energy + elastic_energy + potential_energy; }
};

struct MlsFrameStats {
  int substeps = 0;
  double dt = 0.0;            // s
  double ms_integrate = 0.0;  // first half kick + drift, summed over substeps
  double ms_stress = 0.0;     // pass 1
  double ms_forces = 0.0;     // pass 2 + second half kick
  double ms_reduce = 0.0;
  double ms_coupling = 0.0;  // coupling group pass (eqs. 11-13), summed over substeps
  // All substeps together, when the stages are not timed apart (setStageTiming(false) on the GPU: the frame's
  // substeps replay as one CUDA graph); the per-stage fields above are then zero.
  double ms_substeps = 0.0;
  MlsReduction totals;
  // A frame refused without stepping (totals.bad_stage "timestep"): the substeps it would have needed (0 otherwise).
  double substeps_needed = 0.0;
};

// Coupling groups of the dissection model (section 5.2, physics/cut_coupling.h): group g is one sphere converted
// into nodal points, its member particles (each particle in at most one group), its rest centre and the springs
// that tie it to spheres still simulated by PBD. Every substep the solver computes each group's displacement
// (eq. 13) and spring force and adds the force's per-member share (eqs. 11-12) to its members.
struct MlsCouplingGroups {
  std::vector<std::int32_t> member_offsets{0};  // CSR: group g's particles members[member_offsets[g] .. [g+1])
  std::vector<std::int32_t> members;
  std::vector<Vec3d> rest_centres;              // C_a (m, absolute)
  std::vector<std::int32_t> spring_offsets{0};  // CSR: group g's springs [spring_offsets[g] .. [g+1])
  std::vector<double> rest_lengths;             // m, > 0
  std::vector<double> stiffnesses;              // N/m, >= 0
  std::size_t size() const { return rest_centres.size(); }
  std::size_t springs() const { return rest_lengths.size(); }
};

// Throws InputError("coupling", key, reason) on inconsistent CSR arrays, a particle index out of [0, n), a
// particle in two groups, a group without members, or a non-finite / non-positive spring parameter.
void validateMlsCouplingGroups(const MlsCouplingGroups& groups, std::size_t particles);

// The rest frames of the groups for the rotation-aware eq. 13 (physics/cut_coupling.h), from the particles' rest
// positions: each group's member centroid Xbar (absolute, m), Q = sum q q^T and J = sum (|q|^2 I - q q^T) with
// q = X_i - Xbar (m^2), J^-1, and J's smallest eigenvalue. A group of fewer than 4 members or whose members lie near
// a line (smallest eigenvalue of J under kCouplingMinInertiaRatio of its trace) gets a zero J^-1: it follows the
// plain mean (a rotation about the line would be undetermined, and its moment of inertia would set the step).
constexpr double kCouplingMinInertiaRatio = 0.02;
struct MlsCouplingFrames {
  std::vector<Vec3d> centroid;
  std::vector<Mat3d> gram, inertia_inverse;
  std::vector<double> min_inertia;  // m^2; 0 where the group does not rotate
};
MlsCouplingFrames mlsCouplingFrames(const MlsCouplingGroups& groups, const std::vector<Vec3d>& rest_positions);

// The frames as a solver stores them: precision T, centroids relative to the model origin.
template <typename T>
struct MlsCouplingFrameArrays {
  std::vector<Vec3<T>> centroid;
  std::vector<Mat3<T>> gram, inertia_inverse;
};
template <typename T>
MlsCouplingFrameArrays<T> mlsCouplingFrameArrays(const MlsCouplingFrames& f, const Vec3d& origin) {
  MlsCouplingFrameArrays<T> a;
  for (std::size_t k = 0; k < f.centroid.size(); ++k) {
    a.centroid.push_back(Vec3<T>(f.centroid[k] - origin));
    a.gram.push_back(Mat3<T>(f.gram[k]));
    a.inertia_inverse.push_back(Mat3<T>(f.inertia_inverse[k]));
  }
  return a;
}

// The explicit limit of the groups' rigid modes on their springs (s): min over groups of 2 / omega with omega^2 =
// sum k / m_group (translation; m_group the sum of its members' masses, kg) and, for a rotating group, sum k |C_a -
// Xbar|^2 / (m_min J_min) (rotation about the centroid: the springs' moment arm over the points' least moment of
// inertia, m_min the lightest member); infinity when no group has a spring. `frames` null: translation only.
double mlsCouplingStableStep(const MlsCouplingGroups& groups, const std::vector<double>& masses,
                             const MlsCouplingFrames* frames = nullptr);

// Upper bound on substeps per frame: beyond it a frame would take minutes; refused as bad input.
constexpr std::int64_t kMlsMaxSubsteps = 10000000;

// Substeps for a frame: `fixed` > 0 is used as given unless its step exceeds the stable limit (refused);
// 0 takes ceil(frame_dt / (safety * stable_dt)). Throws InputError naming `key` when refused.
inline int planMlsSubsteps(double frame_dt, double stable_dt, double safety, int fixed, const std::string& file = "",
                           const std::string& key = "solver.substeps") {
  if (!(frame_dt > 0) || !std::isfinite(frame_dt))
    throw InputError(file, "solver.frame_dt_s", "must be a positive number");
  if (fixed > 0) {
    const double dt = frame_dt / fixed;
    if (dt > stable_dt * (1.0 + 1e-12))
      throw InputError(file, key,
                       std::to_string(fixed) + " substeps give dt = " + std::to_string(dt) +
                           " s, above the stable limit " + std::to_string(stable_dt) + " s (needs at least " +
                           std::to_string(std::int64_t(std::ceil(frame_dt / stable_dt))) + "); refused");
    return fixed;
  }
  const double n = std::ceil(frame_dt / (safety * stable_dt) * (1.0 - 1e-12));
  if (!(n <= double(kMlsMaxSubsteps)))
    throw InputError(file, key,
                     "the stable step " + std::to_string(stable_dt) + " s needs " + std::to_string(n) +
                         " substeps per frame; refused (stiffer than the frame rate can afford)");
  return int(std::max(1.0, n));
}

class MlsSolver {
 public:
  virtual ~MlsSolver() = default;
  virtual BackendKind backend() const = 0;
  virtual Precision precision() const = 0;
  virtual std::size_t size() const = 0;
  virtual const MlsModelStats& modelStats() const = 0;
  virtual Vec3d origin() const = 0;                      // rest positions are relative to this (m)
  virtual std::vector<Vec3d> restPositions() const = 0;  // absolute (m)
  // s, safety 1, rest state; with coupling springs (setCouplingGroups) combined with their limit 2 / omega
  // as 1 / sqrt(1/dt_e^2 + 1/dt_c^2), below the true limit 2 / sqrt(omega_e^2 + omega_c^2) of both together.
  double stableTimeStep() const { return withCoupling(modelStats().stable_dt); }
  // The limit at the current deformation (rest limit / sqrt(stiffening) of the last reduction), safety 1.
  double currentStableTimeStep() const {
    return withCoupling(modelStats().stable_dt / std::sqrt(stiffening_ > 1.0 ? stiffening_ : 1.0));
  }
  double safety() const { return safety_; }
  void setSafety(double s) { safety_ = s; }
  // The most substeps advance() takes per call (default kMlsMaxSubsteps); a call that needs more, automatic or fixed,
  // is refused without stepping (see planFrame). The simulations set the frame budget's limit (model/frame_budget.h).
  int maxSubsteps() const { return max_substeps_; }
  void setMaxSubsteps(int n) { max_substeps_ = std::max(1, std::min(n, int(kMlsMaxSubsteps))); }
  // Per-stage timing of advance() (default on). The CUDA solver then launches each substep's kernels one by
  // one between timing events; off, it replays the frame's substeps as one CUDA graph and reports only their
  // total (ms_substeps): small models (a cut's nodal points) are launch-bound. The CPU always times stages.
  virtual void setStageTiming(bool on) { (void)on; }
  // Untimed CUDA frames (setStageTiming(false)): all substeps in one persistent cooperative launch, phases apart by
  // grid-wide barriers (default on; the graph where the device cannot hold the grid at once). Off: the CUDA graph.
  // The same kernels' arithmetic either way, the same bits. The CPU ignores it.
  virtual void setPersistentSubsteps(bool on) { (void)on; }

  // One frame: the substeps stability needs (or exactly `fixed_substeps`, refused when unstable), then the
  // frame reductions. Prescribed particles reach their targets at the end of the frame. Automatic
  // substepping uses the rest-state limit divided by sqrt(stiffening) of the last reduction (computed
  // before the first frame), so a strongly stretched body takes more substeps.
  virtual MlsFrameStats advance(double frame_dt, int fixed_substeps = 0) = 0;
  // advance() then couplingDisplacements(group_u): a coupling exchange's MLS half. The CUDA solver reads the groups'
  // displacements back with the frame's reduction (one wait instead of two); the results are the same.
  virtual MlsFrameStats advanceCoupled(double frame_dt, int fixed_substeps, std::vector<Vec3d>& group_u) {
    MlsFrameStats st = advance(frame_dt, fixed_substeps);
    couplingDisplacements(group_u);
    return st;
  }
  // Exactly n substeps of dt (tests, benchmarks); refuses dt above the stable limit (InputError "dt").
  virtual void step(double dt, int n) = 0;
  // Passes 1 and 2 at the current displacement (forces and per-particle energies), no integration.
  virtual void computeForces() = 0;
  virtual MlsReduction reduce() = 0;

  virtual void setDisplacements(const std::vector<Vec3d>& u) = 0;  // m, one per particle
  virtual void setVelocities(const std::vector<Vec3d>& v) = 0;     // m/s
  virtual void displacements(std::vector<Vec3d>& out) const = 0;
  virtual void velocities(std::vector<Vec3d>& out) const = 0;
  virtual void forces(std::vector<Vec3d>& out) const = 0;     // elastic (+ coupling) forces (N), current u
  virtual void energies(std::vector<double>& out) const = 0;  // v_i psi_i (J), current u
  void positions(std::vector<Vec3d>& out) const;              // origin + X_i + u_i (m)

  // Tools: the listed particles become prescribed, moving linearly to `targets` (displacements, m) over
  // the next frame (or step() call); release() returns them to free dynamics. Fixed particles stay fixed.
  virtual void setPrescribed(const std::vector<std::int32_t>& particles, const std::vector<Vec3d>& targets) = 0;
  virtual void release(const std::vector<std::int32_t>& particles) = 0;

  // Coupling (dissection): set the groups (replaces any earlier; an empty set switches coupling off), the
  // anchors (absolute positions of each spring's PBD sphere, m, held until the next call; zero-length springs
  // before the first call) and read each group's displacement u_a (eq. 13) at the current state.
  virtual void setCouplingGroups(const MlsCouplingGroups& groups) = 0;
  virtual void setCouplingAnchors(const std::vector<Vec3d>& anchors) = 0;
  virtual void couplingDisplacements(std::vector<Vec3d>& out) = 0;

  // The scalpel's capsule over the next advance() or step() (absolute, m): its segment moves from (a0, b0) to
  // (a1, b1) over that call, and free points it covers are put on its surface in every substep
  // (physics/mls_blade_contact.h), sliding on it with Coulomb friction `friction` (0: frictionless). radius 0 (the
  // default) switches it off. Kept until changed.
  void setBladeContact(const Vec3d& a0, const Vec3d& b0, const Vec3d& a1, const Vec3d& b1, double radius,
                       double friction = 0.0) {
    blade_ = {a0, b0, a1, b1, radius, friction};
  }
  // The scene's static colliders (world frame, m) as contacts for the free points in every drift (physics/
  // mls_static_contact.h), each point a ball of `radius` (m; half the sampling spacing puts the sampled surface on
  // them), kept until replaced (also across replaceModel). Throws std::invalid_argument beyond
  // MlsStaticContacts::kMax of a kind (scenes are refused earlier, naming the key) or for a radius < 0.
  void setStaticColliders(const std::vector<pbd::PlaneCollider<double>>& planes,
                          const std::vector<pbd::BoxCollider<double>>& boxes, double radius = 0.0) {
    if (!(radius >= 0.0) || !std::isfinite(radius))
      throw std::invalid_argument("MlsSolver: contact radius must be >= 0");
    if (planes.size() > std::size_t(MlsStaticContacts<double>::kMax) ||
        boxes.size() > std::size_t(MlsStaticContacts<double>::kMax))
      throw std::invalid_argument("MlsSolver: at most " + std::to_string(MlsStaticContacts<double>::kMax) +
                                  " planes and as many boxes");
    planes_ = planes;
    boxes_ = boxes;
    statics_radius_ = radius;
    ++statics_version_;
  }

  virtual void saveCheckpoint() = 0;
  virtual void restoreCheckpoint() = 0;
  virtual MemoryReport memory() const = 0;

  // Replaces the model in place, as a new solver of the same backend and precision would start: state at rest,
  // no coupling groups, no checkpoint, safety from the model (the stage-timing setting is kept). Returns false (model
  // untouched) where a backend keeps nothing worth reusing (the CPU); rebuildMlsSolver then makes a new solver. The
  // CUDA solver keeps its device buffers (grown, never shrunk), its stream, events and executable graph: a cut rebuilds
  // the solver every frame the blade enters spheres, and allocating and freeing ~30 buffers was a third of that.
  virtual bool replaceModel(MlsModel<float>& model) {
    (void)model;
    return false;
  }
  virtual bool replaceModel(MlsModel<double>& model) {
    (void)model;
    return false;
  }

 protected:
  // Substeps for a frame: fixed as given (checked against the rest limit: bad input throws), else automatic
  // at the current limit. Returns 0 when the frame would need more than maxSubsteps() (a physics or budget
  // failure, not bad input: advance() then reports finite == false, stage "timestep", without stepping, and the
  // count it needed in substeps_needed).
  int planFrame(double frame_dt, int fixed_substeps, const std::string& file) {
    substeps_needed_ = 0.0;
    if (fixed_substeps > 0) {
      const int n = planMlsSubsteps(frame_dt, stableTimeStep(), safety_, fixed_substeps, file);
      if (n <= max_substeps_) return n;
      substeps_needed_ = double(n);
      return 0;
    }
    planMlsSubsteps(frame_dt, stableTimeStep(), safety_, 0, file);  // bad input (frame_dt, safety) throws here
    if (!stiffening_known_) stiffening_ = reduce().stiffening;
    const double n = std::ceil(frame_dt / (safety_ * currentStableTimeStep()) * (1.0 - 1e-12));
    if (!(n <= double(max_substeps_))) {
      substeps_needed_ = n;
      return 0;
    }
    return planMlsSubsteps(frame_dt, currentStableTimeStep(), safety_, 0, file);
  }
  // The report of a frame that could not be planned (see planFrame).
  MlsFrameStats unplannableFrame() {
    MlsFrameStats st;
    st.totals = reduce();
    st.totals.finite = false;
    st.totals.bad_stage = "timestep";
    st.totals.first_bad = -1;
    st.substeps_needed = substeps_needed_;
    return st;
  }
  // The blade for n substeps of dt in precision T, relative to the model origin (radius 0: none).
  template <typename T>
  MlsBladeContact<T> bladeContact(double dt, int n) const {
    MlsBladeContact<T> c;
    const Vec3d o = origin();
    c.a0 = Vec3<T>(blade_.a0 - o);
    c.b0 = Vec3<T>(blade_.b0 - o);
    c.a1 = Vec3<T>(blade_.a1 - o);
    c.b1 = Vec3<T>(blade_.b1 - o);
    c.radius = T(blade_.radius);
    c.friction = T(blade_.friction);
    c.duration = T(dt * n);
    c.substeps = n;
    return c;
  }
  bool bladeOn() const { return blade_.radius > 0.0; }
  // The static colliders in precision T, relative to the model origin.
  template <typename T>
  MlsStaticContacts<T> staticContacts() const {
    MlsStaticContacts<T> c;
    c.radius = T(statics_radius_);
    const Vec3d o = origin();
    for (const auto& p : planes_) {
      c.planes[c.planes_n].normal = Vec3<T>(p.normal);
      c.planes[c.planes_n].friction = T(p.friction);
      c.planes[c.planes_n++].offset = T(p.offset - dot(p.normal, o));
    }
    for (const auto& b : boxes_) {
      c.boxes[c.boxes_n].friction = T(b.friction);
      c.boxes[c.boxes_n].min = Vec3<T>(b.min - o);
      c.boxes[c.boxes_n++].max = Vec3<T>(b.max - o);
    }
    return c;
  }
  bool staticsOn() const { return !planes_.empty() || !boxes_.empty(); }
  std::uint64_t staticsVersion() const { return statics_version_; }  // changes with every setStaticColliders
  void forgetStiffening() { stiffening_known_ = false; }             // the state was replaced: measure again
  void setCouplingStableStep(double dt) { coupling_dt_ = dt; }       // s; infinity: no coupling springs
  double withCoupling(double dt) const {
    return std::isfinite(coupling_dt_) ? 1.0 / std::sqrt(1.0 / (dt * dt) + 1.0 / (coupling_dt_ * coupling_dt_)) : dt;
  }
  void resetSolverState(double safety) {  // what a new solver starts with (replaceModel)
    safety_ = safety;
    coupling_dt_ = std::numeric_limits<double>::infinity();
    stiffening_ = 1.0;
    stiffening_known_ = false;
  }
  void noteReduction(const MlsReduction& r) {
    stiffening_ = r.finite ? r.stiffening : stiffening_;
    stiffening_known_ = true;
  }
  struct Blade {
    Vec3d a0, b0, a1, b1;
    double radius = 0.0;
    double friction = 0.0;
  } blade_;
  std::vector<pbd::PlaneCollider<double>> planes_;
  std::vector<pbd::BoxCollider<double>> boxes_;
  std::uint64_t statics_version_ = 0;
  double statics_radius_ = 0.0;
  double safety_ = 0.5;
  int max_substeps_ = int(kMlsMaxSubsteps);  // kept across replaceModel, as the stage-timing setting
  double substeps_needed_ = 0.0;             // the last planFrame's need when it refused (0: it did not)
  double coupling_dt_ = std::numeric_limits<double>::infinity();
  double stiffening_ = 1.0;
  bool stiffening_known_ = false;
};

}  // namespace inc
