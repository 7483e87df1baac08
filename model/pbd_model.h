// PBD/XPBD model (constraint blocks, colliders), state, per-frame inputs and the backend interface both solvers
// implement.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "model/backend.h"
#include "model/graph_coloring.h"
#include "model/input_error.h"
#include "model/stage_timing.h"
#include "physics/pbd_chebyshev.h"
#include "physics/pbd_collision.h"
#include "physics/pbd_rotation.h"
#include "physics/vec3.h"

namespace inc {

enum class PbdConstraintKind : int { Distance = 0, Bending = 1, TetVolume = 2, Laplacian = 3, ShapeMatching = 4 };
enum class PbdSolverKind : int { Jacobi = 0, GaussSeidel = 1 };

const char* pbdConstraintKindName(PbdConstraintKind k);
// "jacobi" | "gauss_seidel"; throws InputError naming `key` otherwise.
PbdSolverKind parsePbdSolver(const std::string& text, const std::string& file, const std::string& key);
// The Chebyshev estimate's rule (physics/pbd_chebyshev.h): in [0, kChebyshevMaxRho], and 0 unless the solver is
// Jacobi. Returns rho; throws InputError(file, key, reason) otherwise.
double checkChebyshevRho(double rho, PbdSolverKind solver, const std::string& file, const std::string& key);

// One kind of constraint. Constraint c touches particles ids[offsets[c] .. offsets[c+1]) (a "slot" is an index
// into ids). Distance: 2 ids; Bending: 4 (edge p0-p1, wings p2, p3); TetVolume: 4; Laplacian: centre then its
// neighbours; ShapeMatching: a cluster, centre sphere first then the other members.
template <typename T>
struct PbdConstraintBlock {
  PbdConstraintKind kind = PbdConstraintKind::Distance;
  bool solve = true;   // false: a ShapeMatching block kept only to estimate rotations
  T stiffness = T(1);  // plain PBD k in [0, 1]
  std::vector<std::int32_t> offsets{0};
  std::vector<std::int32_t> ids;
  std::vector<T> rest;            // Distance: d (m); Bending: psi0 (rad); TetVolume: V0 (m^3); per constraint
  std::vector<Vec3<T>> rest_vec;  // Laplacian: delta0 per constraint (m); ShapeMatching: q per slot (m)
  std::vector<T> compliance;      // XPBD alpha per multiplier (per slot for ShapeMatching, else per constraint)

  // Derived by finalizePbdModel (topology changes only):
  std::vector<std::int32_t> particle_offsets;  // particle p's slots: particle_slots[particle_offsets[p]..[p+1])
  std::vector<std::int32_t> particle_slots;
  std::vector<T> jacobi_scale;  // per slot: 1 / (constraints of this block on the busiest movable
                                // participant); uniform within a constraint except ShapeMatching
  ConstraintColoring coloring;

  std::size_t count() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  std::size_t slotCount() const { return ids.size(); }
  bool perSlotMultiplier() const { return kind == PbdConstraintKind::ShapeMatching; }
  bool vectorMultiplier() const {
    return kind == PbdConstraintKind::Laplacian || kind == PbdConstraintKind::ShapeMatching;
  }
  std::size_t multiplierCount() const { return perSlotMultiplier() ? slotCount() : count(); }
};

template <typename T>
struct PbdModel {
  std::vector<Vec3<T>> rest_positions;        // m
  std::vector<T> masses;                      // kg
  std::vector<T> inv_mass;                    // 1/kg; 0 = fixed (Dirichlet)
  std::vector<T> rest_radii;                  // m; contact radius (0 for mesh vertices)
  std::vector<PbdConstraintBlock<T>> blocks;  // solved in this order each iteration
  int rotation_block = -1;                    // ShapeMatching block whose clusters give per-particle rotations

  // Local volume preservation (physics/pbd_volume.h): spheres that may overlap each sphere, the rest
  // power-cell volumes, and the fixed unit-ball samples both backends use.
  std::vector<std::int32_t> overlap_offsets{0};
  std::vector<std::int32_t> overlap_ids;
  std::vector<T> rest_cell_volume;  // m^3
  std::vector<Vec3<T>> ball_samples;

  std::vector<pbd::PlaneCollider<T>> planes;
  std::vector<pbd::BoxCollider<T>> boxes;
  // Per particle (or empty: none), m in [0, rest radius]: the planes and boxes meet particle i at its radius minus
  // this, so that where its ball bulges beyond the organ's surface, the surface rests on them, not the ball.
  std::vector<T> contact_inset;

  std::size_t size() const { return rest_positions.size(); }
};

template <typename T>
struct PbdStepParams {
  T frame_dt = T(1.0 / 60.0);  // s
  int substeps = 4;            // >= 1; small steps, few iterations (Macklin et al. 2019)
  int iterations = 5;          // >= 1 per substep
  bool xpbd = true;            // false: plain PBD, block stiffness k per projection, no multipliers
  PbdSolverKind solver = PbdSolverKind::Jacobi;
  T jacobi_omega = T(1.5);  // over-relaxation of the averaged Jacobi step, (0, 2)
  T chebyshev_rho = T(0);   // Jacobi: Chebyshev semi-iterative acceleration with this spectral-radius estimate,
                            // [0, 0.9]; 0 off (physics/pbd_chebyshev.h, docs/pbd.md)
  Vec3<T> gravity{T(0), T(0), T(-9.81)};  // m/s^2
  T damping = T(1);                       // 1/s, velocities scaled by exp(-damping dt) each substep
  int rotation_iterations = 4;            // polar-decomposition steps per cluster per projection (warm-started)
  bool volume_preservation = true;
  T volume_influence = T(0);     // m: spheres within this distance of a tool's surface adjust radii; < 0: all
  T max_radius_growth = T(1.5);  // radius stays in [r0, growth * r0]
  int volume_passes = 3;         // Jacobi passes of the radius solve per frame
  int bisection_steps = 12;
  bool use_graph = true;            // CUDA backend: capture the frame in a CUDA graph
  bool profile_stages = false;      // CUDA backend: time each stage with events (no graph, no fusion)
  int fused_max_particles = 4096;   // CUDA backend: models up to this size run all substeps and iterations in one
                                    // single-block kernel (no launch per colour/block); 0 disables; Jacobi models
                                    // use it only up to 256 particles (above, per-block launches measured faster)
  int cluster_max_particles = 256;  // CUDA backend, Jacobi: models up to this size run the frame in one thread-block
                                    // cluster kernel (one launch, hardware barriers between phases) when it can
                                    // (sm_90+, the replica fits shared memory); 0 disables. Measured faster than
                                    // per-block launches up to ~250 spheres (docs/pbd.md)
  int cluster_ctas = 0;           // CUDA cluster frame: CTAs of the cluster (1..16); 0 picks as many as the model needs
  int grid_max_particles = 2048;  // CUDA backend, Jacobi: a frame launched directly (use_graph off, or the first frame
                                  // of a new model) of a model up to this size (not on the cluster frame) runs as one
                                  // cooperative grid launch (grid-wide barriers between phases instead of ~170 kernel
                                  // launches; Chebyshev included); 0 disables. Measured faster up to ~1000
                                  // spheres, slower from ~3000 on an H100 (docs/pbd.md)
};

// What the host prescribes for one frame: kinematic particles move linearly from `from` to `to` over the
// frame's substeps; attached (grasped) particles are pulled towards targets moving likewise by a compliant
// constraint (physics/pbd_block.h projectAttachment); tools are capsules moving linearly likewise.
template <typename T>
struct PbdFrameInput {
  std::vector<std::int32_t> kinematic_ids;
  std::vector<Vec3<T>> kinematic_from, kinematic_to;
  // kinematic_from left empty: each kinematic particle starts the frame where it is (a caller whose state stays on
  // the device need not download those positions only to send them back).
  bool kinematic_from_positions = false;
  std::vector<std::int32_t> attach_ids;         // unique, not kinematic
  std::vector<Vec3<T>> attach_from, attach_to;  // target at the frame's start and end (m)
  std::vector<T> attach_compliance;             // m/N, >= 0
  std::vector<pbd::CapsuleCollider<T>> tools_from, tools_to;
  // The first volume_tools tools also switch on local volume preservation near them (the paper's squeezing tools:
  // graspers, probes); the others are contacts only (a scalpel's blade). -1: every tool.
  int volume_tools = -1;
  int volumeToolCount() const {
    const int n = int(tools_to.size());
    return volume_tools < 0 ? n : (volume_tools < n ? volume_tools : n);
  }
};

template <typename T>
struct PbdState {
  std::vector<Vec3<T>> positions;       // m
  std::vector<Vec3<T>> velocities;      // m/s
  std::vector<T> radii;                 // m (volume preservation changes them)
  std::vector<pbd::Quat<T>> rotations;  // per particle, from its shape-matching cluster (identity if none)
};

struct PbdFrameStats {
  std::vector<StageTime> stages;
  double residual_max = 0.0;  // max |C + alpha~ lambda| over Distance constraints after the last substep (m)
  double residual_rms = 0.0;
  std::string path;       // CUDA: the frame kernel that ran (cluster | grid | fused | launches); empty on the CPU
  int colors = 0;         // Gauss-Seidel: total colours over the solved blocks (0 for Jacobi)
  int iterations = 0;     // constraint iterations this frame (substeps * iterations)
  int volume_active = 0;  // spheres whose radius was solved this frame
  double max_radius_ratio = 1.0;
  bool finite = true;
  std::int64_t failure_particle = -1;
  int threads = 0;            // CPU backend: threads the frame started on (1 while backing off after a stalled team)
  bool team_stalled = false;  // CPU backend: the team stalled and the lead thread finished the frame alone
};

// The state PbdBackend::setModel starts a model in: rest positions, zero velocities, rest radii, identity rotations
// (built here instead of downloaded: a cut installs a new model every frame the blade enters spheres).
template <typename T>
PbdState<T> pbdRestState(const PbdModel<T>& model) {
  PbdState<T> s;
  s.positions = model.rest_positions;
  s.velocities.assign(model.size(), Vec3<T>());
  s.radii = model.rest_radii;
  s.rotations.assign(model.size(), pbd::Quat<T>{});
  return s;
}

template <typename T>
class PbdBackend {
 public:
  virtual ~PbdBackend() = default;
  virtual BackendKind kind() const = 0;
  // Takes the topology (after finalizePbdModel); state := rest, zero velocity, rest radii, identity rotations.
  virtual void setModel(const PbdModel<T>& model) = 0;
  virtual void setState(const PbdState<T>& state) = 0;
  virtual void getState(PbdState<T>& state) const = 0;
  // The positions alone (what a coupling exchange reads between PBD steps): one download instead of four on CUDA.
  virtual void getPositions(std::vector<Vec3<T>>& positions) const {
    PbdState<T> s;
    getState(s);
    positions = std::move(s.positions);
  }
  virtual PbdFrameStats advanceFrame(const PbdStepParams<T>& params, const PbdFrameInput<T>& input) = 0;
  virtual MemoryReport memory() const = 0;
};

// Checks a frame's inputs against a model of n particles (unique in-range kinematic ids, matching sizes,
// finite values, params in range); throws InputError("pbd frame", key, reason).
template <typename T>
inline void validateFrameInput(std::size_t n, const PbdStepParams<T>& p, const PbdFrameInput<T>& in) {
  const char* f = "pbd frame";
  if (!(p.frame_dt > T(0))) throw InputError(f, "frame_dt", "must be > 0");
  if (p.substeps < 1) throw InputError(f, "substeps", "must be >= 1");
  if (p.iterations < 1) throw InputError(f, "iterations", "must be >= 1");
  if (!(p.jacobi_omega > T(0) && p.jacobi_omega < T(2))) throw InputError(f, "jacobi_omega", "must be in (0, 2)");
  checkChebyshevRho(double(p.chebyshev_rho), p.solver, f, "chebyshev_rho");
  if (!(p.damping >= T(0))) throw InputError(f, "damping", "must be >= 0");
  if (!(p.max_radius_growth >= T(1))) throw InputError(f, "max_radius_growth", "must be >= 1");
  if (in.kinematic_from_positions && !in.kinematic_from.empty())
    throw InputError(f, "kinematic_from", "must be empty with kinematic_from_positions");
  if ((!in.kinematic_from_positions && in.kinematic_from.size() != in.kinematic_ids.size()) ||
      in.kinematic_to.size() != in.kinematic_ids.size())
    throw InputError(f, "kinematic", "ids, from and to must have equal sizes");
  std::vector<std::uint8_t> seen(n, 0);
  for (std::size_t k = 0; k < in.kinematic_ids.size(); ++k) {
    const std::int32_t id = in.kinematic_ids[k];
    if (id < 0 || std::size_t(id) >= n) throw InputError(f, "kinematic_ids", "index out of range");
    if (seen[id]) throw InputError(f, "kinematic_ids", "duplicate index " + std::to_string(id));
    seen[id] = 1;
    if ((!in.kinematic_from_positions && !isFinite(in.kinematic_from[k])) || !isFinite(in.kinematic_to[k]))
      throw InputError(f, "kinematic", "not finite");
  }
  if (in.attach_from.size() != in.attach_ids.size() || in.attach_to.size() != in.attach_ids.size() ||
      in.attach_compliance.size() != in.attach_ids.size())
    throw InputError(f, "attach", "ids, from, to and compliance must have equal sizes");
  for (std::size_t k = 0; k < in.attach_ids.size(); ++k) {
    const std::int32_t id = in.attach_ids[k];
    if (id < 0 || std::size_t(id) >= n) throw InputError(f, "attach_ids", "index out of range");
    if (seen[id]) throw InputError(f, "attach_ids", "index " + std::to_string(id) + " is duplicate or kinematic");
    seen[id] = 1;
    if (!isFinite(in.attach_from[k]) || !isFinite(in.attach_to[k])) throw InputError(f, "attach", "not finite");
    if (!(in.attach_compliance[k] >= T(0)) || !std::isfinite(double(in.attach_compliance[k])))
      throw InputError(f, "attach_compliance", "must be finite and >= 0");
  }
  if (in.tools_from.size() != in.tools_to.size()) throw InputError(f, "tools", "from and to must have equal sizes");
  const auto bad = [](const pbd::CapsuleCollider<T>& c) {
    return !(c.radius >= T(0)) || !isFinite(c.a) || !isFinite(c.b) || !(c.friction >= T(0) && c.friction <= T(2));
  };
  for (std::size_t k = 0; k < in.tools_from.size(); ++k)
    if (bad(in.tools_from[k]) || bad(in.tools_to[k]))
      throw InputError(f, "tools", "capsule not finite, negative radius, or friction outside [0, 2]");
}

// A block's particle -> slot CSR from its ids (n particles): a counting sort, so each particle's slots are
// ascending (the deterministic gather order). finalizePbdModel's first derived step, also for builders that
// derive the rest themselves.
template <typename T>
void fillParticleSlots(PbdConstraintBlock<T>& b, std::size_t n) {
  b.particle_offsets.assign(n + 1, 0);
  for (std::int32_t p : b.ids) ++b.particle_offsets[std::size_t(p) + 1];
  for (std::size_t p = 0; p < n; ++p) b.particle_offsets[p + 1] += b.particle_offsets[p];
  b.particle_slots.resize(b.ids.size());
  std::vector<std::int32_t> fill(b.particle_offsets.begin(), b.particle_offsets.end() - 1);
  for (std::size_t s = 0; s < b.ids.size(); ++s)
    b.particle_slots[std::size_t(fill[std::size_t(b.ids[s])]++)] = std::int32_t(s);
}

// Fills the derived data of every block (particle->slot CSR, Jacobi scales, colouring unless `coloring` is
// false: a Jacobi-only model, on which both backends refuse Gauss-Seidel) and validates the model; throws
// InputError(file "pbd model", key, reason) on inconsistent sizes or indices.
template <typename T>
void finalizePbdModel(PbdModel<T>& model, bool coloring = true);

// Whether every solved, non-empty block has a colouring (Gauss-Seidel needs one).
template <typename T>
bool pbdModelHasColoring(const PbdModel<T>& model) {
  for (const auto& b : model.blocks)
    if (b.solve && b.count() > 0 && b.coloring.order.size() != b.count()) return false;
  return true;
}

// Rest power-cell volumes and ball samples for volume preservation (needs overlap lists and rest radii); `known`:
// per particle a volume to take as it is (NaN: compute it).
template <typename T>
void computeRestCellVolumes(PbdModel<T>& model, int sample_count, const std::vector<double>* known = nullptr);

}  // namespace inc
