// The built-in scenes (JSON text in the binary); the default is what the README's first command runs.
#include "host/scene/embedded_scenes.h"

#include "embedded_default_scene.h"  // generated from scenes/steak_cut.json

namespace inc {
namespace {

// A soft-tissue cantilever (8 x 2 x 2 cm, E = 200 kPa) clamped at x = min and sagging under its own
// weight: the MLS solver's reference case (scenes/beam.json is the same body at a finer 2.5 mm spacing).
// The 4 mm spacing (500 particles) keeps the CPU fallback near real time for the README's first command.
const char* kBeamJson = R"json({
  "name": "beam",
  "description": "MLS meshfree cantilever (500 particles) clamped at one end, sagging under its own weight",
  "duration_s": 0.5,
  "geometry": {"kind": "beam", "center_m": [0.04, 0.0, 0.0], "size_m": [0.08, 0.02, 0.02],
               "spacing_m": 0.004, "jitter": 0.0, "seed": 1},
  "material": {"youngs_modulus_pa": 2.0e5, "poisson_ratio": 0.4, "density_kg_m3": 1060.0,
               "damping_per_s": 10.0},
  "models": {"mls": true},
  "mls": {"support_factor": 2.0, "volume_preservation": true, "volume_stiffness": 1.0, "condition_limit": 1.0e6},
  "solver": {"frame_dt_s": 0.016666666666666666, "substeps": 0, "safety": 0.5,
             "precision": "float32", "backend": "auto", "gravity_m_s2": [0.0, 0.0, -9.81]},
  "fixed": [{"min_m": [-0.001, -0.011, -0.011], "max_m": [0.0041, 0.011, 0.011]}],
  "output": {"every_frames": 0, "particles_ply": true, "mesh_obj": true, "vtk": true, "metrics_csv": true}
})json";

// The first is the default: the product's core case (issue 6), a block of metaballs cut through by a scalpel,
// its nodal points simulated by MLS while the blade is in and re-packed per side when it leaves, the surface
// split with both cut walls. About 1.5 s on two CPU cores for its 0.8 s of simulated time.
const std::vector<EmbeddedScene> kScenes = {
    {kDefaultSceneName, "a steak-like block cut straight through by a scalpel (PBD metaballs + MLS nodal points)",
     kDefaultSceneJson},
    {"beam", "MLS cantilever beam sagging under gravity (CPU or GPU)", kBeamJson},
};

}  // namespace

const std::vector<EmbeddedScene>& embeddedScenes() { return kScenes; }

const EmbeddedScene& defaultEmbeddedScene() { return kScenes.front(); }

const EmbeddedScene* findEmbeddedScene(const std::string& name) {
  for (const auto& s : kScenes)
    if (name == s.name) return &s;
  return nullptr;
}

}  // namespace inc
