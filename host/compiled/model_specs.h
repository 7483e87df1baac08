// What a scene says about each model, in SI units: the geometry, the models switched on, each solver's settings,
// fixed regions, tools, colliders, tearing, cutting and haptics (docs/scene-format.md names every key). The parts
// of a CompiledScene (host/compiled/compiled_scene.h): the layers below the application read these, never a Scene.
#pragma once

#include <string>
#include <vector>

#include "model/backend.h"
#include "physics/vec3.h"

namespace inc {

struct GeometrySpec {
  enum class Kind { Box, Beam, Sphere, Ellipsoid, Mesh };
  Kind kind = Kind::Beam;
  Vec3d center{0, 0, 0};          // m
  Vec3d size{0.1, 0.02, 0.02};    // m, full extents (box, beam: beam is a box whose long axis is x)
  double radius = 0.05;           // m (sphere)
  Vec3d radii{0.05, 0.03, 0.02};  // m (ellipsoid semi-axes)
  std::string mesh_path;          // resolved against the scene file's folder (mesh)
  double mesh_scale = 1.0;        // multiplies mesh coordinates to get metres
  double spacing = 0.005;         // m, particle spacing for meshfree sampling; > 0
  double jitter = 0.0;            // fraction of spacing, [0, 0.5): random offset of the sample lattice
  unsigned seed = 1;              // for jitter and every random choice of the scene
};

// Which models the scene switches on; a scene pays only for those.
struct ModelsSpec {
  bool mls = false;            // meshfree MLS elasticity (issue 4)
  bool pbd_metaballs = false;  // metaball organ driven by PBD/XPBD (issue 5)
  bool cutting = false;        // dissection (issue 6)
  bool tearing = false;        // Tresca tearing (issue 7)
  bool haptics = false;        // haptic thread and force models (issue 8)
};

struct MlsSpec {
  double support_factor = 2.0;      // h = support_factor * spacing; [1.2, 4]
  bool volume_preservation = true;  // penalty on det F - 1
  double volume_stiffness = 1.0;    // penalty modulus as a multiple of the bulk modulus, >= 0
  double condition_limit = 1.0e6;   // A_i with a larger condition number gets a regularised inverse
};

struct PbdSpec {
  int iterations = 10;              // >= 1
  bool xpbd = true;                 // false: plain PBD (stiffness depends on iterations/dt)
  std::string solver = "jacobi";    // "jacobi" | "gauss_seidel"
  double chebyshev_rho = 0.0;       // Jacobi: Chebyshev acceleration's spectral-radius estimate, [0, 0.9]; 0 off
  double stretch_compliance = 0.0;  // m/N (XPBD alpha), >= 0
  double laplacian_compliance = 0.0;
  bool volume_preservation = true;
  int target_spheres = 0;  // 0: choose from the mesh size
};

struct SolverSpec {
  double frame_dt = 1.0 / 60.0;  // s, > 0: one frame of output/rendering
  int substeps = 0;              // 0: as many as stability needs; > 0: exactly this many (refused if unstable)
  double safety = 0.5;           // fraction of the stable explicit step to use, (0, 1]
  int max_substeps = 0;  // substeps a frame may take (refused beyond); 0: from the frame budget (frame_budget.h)
  Precision precision = Precision::Float32;
  BackendKind backend = BackendKind::Auto;
  Vec3d gravity{0, 0, -9.81};   // m/s^2
  double energy_bound = 1.0e3;  // blow-up guard: stop if total energy exceeds this factor times its reference
};

// Particles whose rest position lies inside are held fixed (Dirichlet).
struct FixedRegion {
  Vec3d min{0, 0, 0}, max{0, 0, 0};  // axis-aligned box, m
};

struct ToolKeyframe {
  double t = 0.0;             // s
  Vec3d position;             // m (tool tip / blade centre)
  Vec3d direction{0, 0, -1};  // unit: blade edge direction or grasp axis
};

struct ToolSpec {
  std::string name;
  std::string kind = "probe";      // "probe" | "grasper" | "scalpel"
  double radius = 0.002;           // m, capsule radius around the tool
  double length = 0.02;            // m, blade length (scalpel)
  double friction = 0.0;           // [0, 2], Coulomb coefficient of its contact with PBD spheres (probe, open grasper);
                                   // a scalpel's is cutting.blade_friction
  std::vector<ToolKeyframe> path;  // piecewise-linear in time, sorted by t
};

// Tearing of the PBD sheet (models.tearing, issue 7; docs/tearing.md). A region overrides k and tau_f of the
// particles whose rest position lies inside (later regions win); 0 there keeps the section's value.
struct TearingRegionSpec {
  Vec3d min{0, 0, 0}, max{0, 0, 0};  // axis-aligned box, m
  double k_pa = 0.0;                 // Pa, >= 0; 0: the section's k
  double tau_f_pa = 0.0;             // Pa, >= 0; 0: the section's tau_f
};

struct TearingSpec {
  std::string criterion = "tresca";  // "traditional" | "tresca" | "tresca_principal"
  double k_pa = 0.0;                 // Pa, >= 0: eq. 6 modulus; 0: material.youngs_modulus_pa
  double tau_f_pa = 0.0;             // Pa, >= 0: yield shear stress; 0: 0.1 k
  double break_strain = 0.2;         // > 0: bond strain at which the traditional criterion breaks a bond
  double random_range = 0.1;         // [0, 1): relative perturbation of the debris position (the paper's 10 %)
  unsigned seed = 1;                 // the debris random stream
  std::vector<TearingRegionSpec> regions;
};

// Dissection (models.cutting, issue 6; docs/cutting.md): nodal sampling, the PBD <-> MLS synchronisation of
// section 5.3 while nodal points exist, and the re-packing of Algorithm 1.
struct CuttingSpec {
  int samples_per_diameter = 4;         // [2, 12]: nodal lattice cells across a converted sphere's diameter
  int exchanges_per_frame = 4;          // [1, 64]: coupling exchanges (forces to the points, eq. 13 back) per frame
  int pbd_substeps_per_exchange = 1;    // [1, 64]: PBD substeps between two exchanges
  int pbd_iterations = 0;               // [0, 1000]: PBD iterations per substep while points exist; 0: pbd.iterations
  int mls_substeps_per_exchange = 0;    // [0, 100000]: 0: as many as the points' stable explicit step needs
  double repack_boundary_offset = 0.3;  // (0, 1): one-sided neighbourhood (centroid offset / support) = boundary
  double repack_spacing_factor = 0.5;  // (0, 4]: eq. 14's factor, d = factor * max distance of medial points to the cut
  double repack_sphere_budget = 1.0;   // (0, 8]: new spheres per converted sphere's mass, per group (merging)
  int stroke_end_frames = 0;           // [0, 120]: frames from the blade leaving to the cut applied (a worker
                                       // re-packs, splits and binds meanwhile); 0: in the frame it leaves
  int conversion_delay_frames = 0;     // [0, 1]: frames from the blade entering spheres to their conversion
                                       // applied (prepared on workers meanwhile); 0: in the frame it enters
  int open_surface_frames = 0;         // [0, 120]: during a stroke, the surface split along the sweep so far is
                                       // computed on a worker and shown this many frames later (display only);
                                       // 0: the surface opens when the stroke ends
  double blade_radius_m = 0.0;         // [0, 0.05]: the blade's contact capsule (pushes spheres and points it
                                       // does not cut); 0: the blade only cuts
  double blade_friction = 0.0;         // [0, 2]: Coulomb coefficient of the nodal points sliding on that capsule
};

// One haptic device of a scene and its loop (docs/scene-format.md `haptics`, docs/haptics.md): the single-device
// form's keys sit in `haptics` itself, the list form's in each `haptics.devices[i]`.
struct HapticDeviceSpec {
  std::string name;                        // unique among the devices; "" in the single-device form
  std::string device = "scripted";         // "scripted" | "udp" | "openhaptics"
  std::string trajectory;                  // scripted: trajectory file (absolute once loaded; docs/haptics.md format)
  std::string playback = "time";           // scripted: "time" (interpolate by loop time) | "tick" (bit-exact replay)
  int udp_port = 47000;                    // udp: 127.0.0.1 port, [1, 65535]
  int udp_device = 0;                      // udp: device id in the datagrams, [0, 65535]
  std::string openhaptics_device;          // openhaptics: configuration name; "" = the default device
  double workspace_scale = 1.0;            // openhaptics: scene metres per device metre, > 0
  Vec3d workspace_offset_m{0, 0, 0};       // openhaptics: scene position of the device origin
  double max_force_n = 3.3;                // clamp (scripted/udp; openhaptics reads its own), > 0
  double rate_hz = 1000.0;                 // loop rate, [100, 10000]
  double max_force_rate_n_per_s = 1000.0;  // rate limiter, > 0
  bool realtime = true;                    // ask SCHED_FIFO for the loop thread
  int cpu = -1;                            // >= 0: pin the loop thread to this CPU
  std::string tool = "auto";               // "auto" | "scalpel" | "probe" (auto: the first device on a model that can
                                           // be cut holds the scalpel, every other device a probe)
  double blade_length_m = 0.05;            // scalpel: the blade segment centred on the tip, > 0
  Vec3d blade_axis{0, 0, 1};               // scalpel: blade direction in the device frame (normalised on load)
};

// The haptic loops of a scene with models.haptics (docs/scene-format.md `haptics`, docs/haptics.md). Read by the
// runner (`incision run`: one loop per device) and the viewer (`incision view`: the mouse drives the first device).
struct HapticsSpec {
  std::vector<HapticDeviceSpec> devices{HapticDeviceSpec{}};  // one per hand: 1 to 4
  bool devices_listed = false;        // the scene used the list form (`haptics.devices`); written back the same
  bool has_surface_point = false;     // false: the organ's highest point along surface_normal
  Vec3d surface_point_m{0, 0, 0};     // the tissue plane of the tools' contact model
  Vec3d surface_normal{0, 0, 1};      // its outward unit normal (normalised on load)
  double local_radius_m = 0.008;      // MFS local model: half-ball radius around the tip, > 0
  double local_spacing_m = 0.002;     // MFS local model: inner node spacing, (0, local_radius_m / 2]
  bool record_trajectory = false;     // write each device's trajectory (hex floats) and tick forces to --out
  std::string global_model = "none";  // "none" (the local model with a held boundary) | "bem" (hybrid MFS + BEM)
  std::string global_mesh;            // bem: the organ's closed surface mesh (absolute once loaded)
  double global_mesh_scale = 1.0;     // bem: metres per mesh file unit, > 0
  std::string global_cache;           // bem: the precompute's cache file (absolute once loaded)
};

// A static collider (`colliders[k]`, docs/scene-format.md): the organ's spheres and nodal points stay out of it,
// with Coulomb friction.
struct ColliderSpec {
  std::string kind = "plane";  // "plane" | "box"
  Vec3d normal{0, 0, 1};       // plane: unit (normalised on load), pointing to the free side
  Vec3d point;                 // plane: a point on it (m)
  Vec3d min, max;              // box: its corners (m), min < max in every component
  double friction = 0.0;       // [0, 2]: Coulomb coefficient against the organ (0: frictionless)
};
constexpr int kMaxCollidersPerKind = 8;  // planes, and boxes, per scene (each contact runs in every substep)

// The key path of device `index`'s `key`, for messages: "haptics.<key>" in the single-device form, else
// "haptics.devices[index].<key>".
inline std::string hapticDeviceKey(const HapticsSpec& h, std::size_t index, const std::string& key) {
  return h.devices_listed ? "haptics.devices[" + std::to_string(index) + "]." + key : "haptics." + key;
}

}  // namespace inc
