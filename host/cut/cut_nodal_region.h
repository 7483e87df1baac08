// The nodal points of one scalpel stroke (sections 5.1-5.3): spheres converted into MLS points while the blade is in
// the tissue, their visibility-filtered supports, the MLS solver and the coupling groups that tie them to the PBD
// spheres.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/backends/solver_factory.h"
#include "host/compiled/model_specs.h"
#include "host/compiled/scene_colliders.h"
#include "host/cut/cut_repack.h"
#include "host/cut/cut_stroke_supports.h"
#include "host/cut/cut_swept_surface.h"
#include "model/backend.h"
#include "model/mls_model.h"
#include "model/mls_solver.h"

namespace inc {

// What a sphere of the stroke's base model is now: simulated by PBD, converted into points but still in the PBD
// model as a kinematic sphere driven by its points (an interface sphere: its points are the "overlapping points"
// of section 5.2), or converted and gone from the PBD model (a cut sphere).
enum class SphereRole : std::uint8_t { Pbd = 0, Interface = 1, Cut = 2 };

struct NodalRegionSettings {
  int samples_per_diameter = 4;            // lattice cells across a converted sphere's (mean) diameter
  MlsBuildInput mls;                       // material, support_factor, condition_limit, gravity, safety, source; its
                                           // youngs_modulus_pa also sets the links: k = 1 / alpha as the PBD links
  BackendKind backend = BackendKind::Cpu;  // resolved (Cpu or Cuda)
  Precision precision = Precision::Float32;
  std::vector<FixedRegion> fixed;            // a sphere whose rest centre lies inside is fixed: so are its points
  double stretch_compliance = 0.0;           // m/N; 0: alpha = d / (E pi rbar^2) (host/assembly/pbd_builders.h)
  std::function<bool(const Vec3d&)> inside;  // the tissue: points are sampled only inside it (empty: everywhere)
  StaticColliders colliders;                 // the scene's planes and boxes: the points stay out of them
  // The frame budget (model/frame_budget.h): solver.max_substeps (0: automatic for the points' count), shared by
  // the frame's exchanges_per_frame advance() calls.
  int max_substeps = 0;
  int exchanges_per_frame = 1;
};

// A sphere's state when it is converted: its points start rigidly attached, x = x_b + R_b (X - C_b), v = v_b.
struct ConvertedSphereState {
  Vec3d position, velocity;            // m, m/s
  Mat3d rotation = Mat3d::identity();  // the sphere's shape-matching rotation
};

// What the stroke leaves when the blade exits: the cut spheres' points for re-packing (Algorithm 1) with their
// state, and the interface spheres' state by eq. 13 (they return to PBD).
struct NodalRegionFinal {
  RepackPoints points;                        // all points (the interface spheres' as context), rest configuration
  std::vector<Vec3d> displacement, velocity;  // per point of `points` (m, m/s)
  std::vector<std::int32_t> interface_ids;    // base indices
  std::vector<Vec3d> interface_position, interface_velocity;  // eq. 13 position, mean velocity of its points
};

// The rest configuration of a stroke's points: everything a conversion changes, and nothing that moves (the
// solver's state stays in NodalRegion). A conversion is worked out on its own copy (NodalUpdate), so that it can be
// prepared on a worker while the points go on being simulated with the current one.
struct NodalRest {
  std::vector<SphereRole> role;                          // per base sphere
  std::vector<std::vector<std::int32_t>> sphere_points;  // base sphere -> its points
  std::vector<Vec3d> rest;                               // per point (m)
  std::vector<double> mass;                              // kg
  std::vector<std::int32_t> source;                      // the base sphere a point was sampled from
  std::vector<std::uint8_t> kind;                        // MlsParticleKind
  std::set<std::array<std::int64_t, 3>> occupied;        // lattice cells already holding a point
  StrokeSupports supports;                               // visibility-filtered supports, kept across the stroke
  MlsCouplingGroups groups;                              // group g belongs to base sphere group_sphere[g]
  std::vector<std::int32_t> group_sphere;
  std::vector<std::int32_t> spring_other;  // per spring: the base index of its PBD sphere
};

// A conversion, or a strip that only cuts supports, worked out in the rest configuration alone
// (NodalRegion::prepareConversion / prepareStrip): the next rest data and, where the points or their supports
// changed, the MLS model built on them. NodalRegion::apply brings it in with the state of a later moment.
struct NodalUpdate {
  NodalRest next;
  std::vector<std::int32_t> sampled;  // base spheres whose points this update adds, in the order it adds them
  std::size_t first_new = 0;          // next.rest[first_new ..] are those points
  bool rebuild = false;               // the points or the supports changed: `model` is the MLS model on them
  MlsBuiltModel model;
  // The MLS solver already loaded with `model`, its groups and the scene's colliders on a worker (preload); apply()
  // then only transfers the state into it. Null: apply() loads the model itself.
  std::unique_ptr<MlsSolver> preloaded;
  std::size_t changed = 0;                                    // spheres that changed role
  std::size_t removed = 0;                                    // directed supports the strip dropped
  double sample_ms = 0, supports_ms = 0, model_build_ms = 0;  // host time of the parts (ms)
};

class NodalRegion {
 public:
  // `base`: the sphere model when the stroke began (its indices are the "base" indices used below).
  // `earlier_cuts`: cuts applied before this stroke (visibility), kept by pointer: they must outlive the region.
  NodalRegion(const MetaballModel& base, const NodalRegionSettings& settings,
              std::vector<const SweptSurface*> earlier_cuts);

  const MetaballModel& base() const { return base_; }
  SphereRole role(std::int32_t b) const { return r_.role[std::size_t(b)]; }
  const std::vector<SphereRole>& roles() const { return r_.role; }
  std::size_t pointCount() const { return r_.rest.size(); }
  bool active() const { return !r_.rest.empty(); }
  std::size_t interfaceCount() const;
  std::size_t springCount() const { return r_.groups.springs(); }
  double pointSpacing() const { return spacing_; }
  double pointMass() const;                                              // kg, sum over the points
  std::size_t supportsRemoved() const { return r_.supports.removed(); }  // directed pairs dropped by the cuts so far
  double lastRebuildMs() const { return last_rebuild_ms_; }              // the last apply's MLS solver load and setup
  // The parts of the last conversion (ms): sampling, supports and the MLS model's host build (the update's
  // preparation), the model built and loaded, the rest of the load (groups, state and anchor uploads, the
  // stable-step reduction).
  struct ConversionTimes {
    double sample_ms = 0, supports_ms = 0, model_ms = 0, setup_ms = 0;
    double model_build_ms = 0;  // of model_ms: the host build (prepared apart from the load)
  };
  const ConversionTimes& lastConversionTimes() const { return times_; }
  const MlsSolver* solver() const { return solver_.get(); }
  const NeighborLists& supports() const { return r_.supports.lists(); }
  const std::vector<Vec3d>& restPoints() const { return r_.rest; }
  const std::vector<std::int32_t>& pointSphere() const { return r_.source; }

  // The roles after converting the listed base spheres: each becomes Cut, its PBD-role link neighbours Interface.
  std::vector<SphereRole> rolesAfter(const std::vector<std::int32_t>& cut) const;

  // The rest data an update starts from: a copy (an update prepared while advance() runs: prepare* read nothing
  // advance() writes) or the region's own, moved out (an update applied at once; nothing but prepare* and apply
  // may use the region in between).
  NodalRest restCopy() const { return r_; }
  NodalRest takeRest() { return std::move(r_); }
  // Converts the listed base spheres (rolesAfter), sampling the ones without points yet (section 5.1, rest
  // positions only), and updates the supports for the new points and the stroke so far (`stroke`: the swept
  // surface, extending the one of the previous update, else the supports start over; visibility against the stroke
  // and the earlier cuts, the same lists as visibleSupports from scratch), then the coupling groups and the MLS
  // model (moment matrices of every point recomputed).
  NodalUpdate prepareConversion(NodalRest from, const std::vector<std::int32_t>& cut, const SweptSurface& stroke) const;
  // The stroke grew by `fresh` (a surface holding only the new triangles, the next ones of the stroke the next
  // conversion gets): supports crossing it are dropped and, if any was, the groups and the MLS model are rebuilt.
  NodalUpdate prepareStrip(NodalRest from, const SweptSurface& fresh) const;
  // Brings `u` in: the existing points keep their state, the new points start rigidly attached to their sphere,
  // x = x_b + R_b (X - C_b), v = v_b, from `sampled_state` (one per u.sampled, the spheres' state now); the MLS
  // solver is loaded with u's model.
  void apply(NodalUpdate& u, const std::vector<ConvertedSphereState>& sampled_state);
  // Loads u's model into the region's spare solver (device buffers of the solver before last) with the rest data
  // apply() would load: the groups, the scene's colliders, untimed stages. For a worker thread while advance() runs
  // on the current solver: it touches only the spare, and holds deviceCaptureMutex() for the device work. Nothing
  // when u needs no rebuild.
  void preload(NodalUpdate& u);
  // prepareConversion on the region's own data then apply, with `state(b)` a sphere's state now. Returns the
  // number of spheres that changed role.
  std::size_t convert(const std::vector<std::int32_t>& cut,
                      const std::function<ConvertedSphereState(std::int32_t)>& state, const SweptSurface& stroke);
  // prepareStrip then apply, on the region's own data. Returns the pairs dropped.
  std::size_t cutSupports(const SweptSurface& fresh);

  // One coupling exchange: the springs' anchors from the PBD spheres' current positions (`pbd_position(j)` for
  // base index j), then `dt` of MLS (eqs. 4-10 with the springs of eqs. 11-12 every substep). `fixed_substeps`
  // > 0 takes at least that many (more when the stable step needs them). Updates the groups' eq. 13 state.
  // An exchange that needs more substeps than its share of the frame's limit (substepLimit()) is refused without
  // stepping: finite false, stage "timestep", the count in substeps_needed.
  MlsFrameStats advance(double dt, int fixed_substeps, const std::function<Vec3d(std::int32_t)>& pbd_position);
  // The scalpel as a contact for the points over the next advance (world = the points' frame, m): its blade moves
  // from `from` to `to`; points within `radius` of it are put on its surface, sliding with Coulomb friction
  // `friction` (MlsSolver::setBladeContact). radius 0: none (the default).
  void setBlade(const BladePose& from, const BladePose& to, double radius, double friction = 0.0) {
    blade_from_ = from;
    blade_to_ = to;
    blade_radius_ = radius;
    blade_friction_ = friction;
  }

  // eq. 13: the position (C_a + u_a) of every interface sphere after the last advance (or conversion).
  void interfacePositions(std::vector<std::int32_t>& ids, std::vector<Vec3d>& positions) const;
  // The displacement (m) of base sphere b as the skin sees it near rest point p: a converted sphere's by eq. 13
  // of its point group nearest p (a cut sphere has one group per piece of it), else nothing (returns false).
  bool sphereDisplacement(std::int32_t b, const Vec3d& p, Vec3d& out) const;
  // Stored energy of the coupling springs, sum k/2 (l' - l)^2 (J), at the last anchors.
  double springEnergy() const;
  // Kinetic, elastic and gravity energy of the points (J) and their largest displacement (m): the last reduction.
  const MlsReduction& lastReduction() const { return last_reduction_; }

  void saveCheckpoint();
  void restoreCheckpoint();
  void scaleSafety(double factor);
  // The substeps one advance() may take: the frame's limit for the current points over exchanges_per_frame.
  int substepLimit() const;
  std::string substepLimitRule() const;  // how that limit follows from the settings, for messages

  // The points a re-pack takes (rest configuration: the cut spheres' points, the interface spheres' as context, and
  // the supports among them all). Depends on nothing that moves: fixed once the stroke stops converting.
  RepackPoints repackPoints() const;
  // Ends the stroke: the state the PBD side needs back (with the points of repackPoints() when `with_points`). The
  // region is empty afterwards (no nodal points).
  NodalRegionFinal finish(bool with_points = true);

 private:
  struct Link {
    std::int32_t other;
    double rest, stiffness;
  };
  void sample(NodalRest& next, const std::vector<std::int32_t>& batch) const;
  void regroup(NodalRest& r) const;
  void build(NodalUpdate& u) const;  // groups and MLS model on u.next
  void syncState();                  // host copies of u, v from the solver

  MetaballModel base_;
  NodalRegionSettings settings_;
  std::vector<const SweptSurface*> earlier_;
  std::vector<std::vector<Link>> adjacency_;  // base links per sphere with their spring stiffness
  double spacing_ = 0.0;                      // m, the shared sampling lattice's spacing
  NodalRest r_;
  std::vector<Vec3d> u_, v_;  // host copies of the points' state (valid after syncState)
  std::vector<Vec3d> group_u_, anchors_;
  std::unique_ptr<MlsSolver> solver_;
  std::unique_ptr<MlsSolver> spare_;
  void loadRestData(MlsSolver& s, const MlsCouplingGroups& groups)
      const;  // the solver before last: preload() loads the next model into its buffers
  MlsReduction last_reduction_;
  double safety_scale_ = 1.0;
  double last_rebuild_ms_ = 0.0;
  BladePose blade_from_, blade_to_;
  double blade_radius_ = 0.0, blade_friction_ = 0.0;
  ConversionTimes times_;
};

}  // namespace inc
