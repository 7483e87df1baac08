// The built-in scenes (JSON text in the binary); the default is what the README's first command runs.
#include "host/embedded_scenes.h"

namespace inc {
namespace {

// A tissue-like cantilever (10 cm x 2 cm x 2 cm, E = 500 kPa) clamped at x < 0 and sagging under
// gravity: the MLS solver's reference case, with an Euler-Bernoulli answer to compare against.
const char* kBeamJson = R"json({
  "name": "cantilever-beam",
  "description": "MLS meshfree cantilever clamped at one end, sagging under its own weight",
  "duration_s": 1.0,
  "geometry": {"kind": "beam", "center_m": [0.05, 0.0, 0.0], "size_m": [0.1, 0.02, 0.02],
               "spacing_m": 0.0025, "jitter": 0.0, "seed": 1},
  "material": {"youngs_modulus_pa": 5.0e5, "poisson_ratio": 0.4, "density_kg_m3": 1000.0,
               "damping_per_s": 20.0},
  "models": {"mls": true},
  "mls": {"support_factor": 2.0, "volume_preservation": true, "volume_stiffness": 0.1},
  "solver": {"frame_dt_s": 0.016666666666666666, "substeps": 0, "safety": 0.5,
             "precision": "float32", "backend": "auto", "gravity_m_s2": [0.0, 0.0, -9.81]},
  "fixed": [{"min_m": [-0.001, -0.011, -0.011], "max_m": [0.0026, 0.011, 0.011]}],
  "output": {"every_frames": 0, "particles_ply": true, "mesh_obj": true, "vtk": true, "metrics_csv": true}
})json";

const std::vector<EmbeddedScene> kScenes = {
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
