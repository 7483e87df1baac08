// The dissection model's checks of its scene: the keys it needs, the cutting ranges, the scalpels' timing.
#include "host/sim/dissection_scene_checks.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "host/assembly/mls_model_build.h"
#include "model/input_error.h"
#include "physics/mls_integrate.h"

namespace inc::dissection {

namespace {

void checkCuttingRanges(const CompiledScene& s) {
  const CuttingSpec& c = s.cutting;
  const auto range = [&](int v, int lo, int hi, const char* key) {
    if (v < lo || v > hi)
      throw InputError(
          s.file, std::string("cutting.") + key,
          "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " + std::to_string(v) + ")");
  };
  range(c.samples_per_diameter, 2, 12, "samples_per_diameter");
  range(c.exchanges_per_frame, 1, 64, "exchanges_per_frame");
  range(c.pbd_substeps_per_exchange, 1, 64, "pbd_substeps_per_exchange");
  range(c.pbd_iterations, 0, 1000, "pbd_iterations");
  range(c.mls_substeps_per_exchange, 0, 100000, "mls_substeps_per_exchange");
  range(c.stroke_end_frames, 0, 120, "stroke_end_frames");
  range(c.conversion_delay_frames, 0, 1, "conversion_delay_frames");
  range(c.open_surface_frames, 0, 120, "open_surface_frames");
  if (!(c.blade_radius_m >= 0 && c.blade_radius_m <= 0.05))
    throw InputError(s.file, "cutting.blade_radius_m", "must lie in [0, 0.05] m");
  if (!(c.blade_friction >= 0 && c.blade_friction <= 2))
    throw InputError(s.file, "cutting.blade_friction", "must lie in [0, 2]");
  if (!(c.repack_boundary_offset > 0 && c.repack_boundary_offset < 1))
    throw InputError(s.file, "cutting.repack_boundary_offset", "must lie in (0, 1)");
  if (!(c.repack_spacing_factor > 0 && c.repack_spacing_factor <= 4))
    throw InputError(s.file, "cutting.repack_spacing_factor", "must lie in (0, 4]");
  if (!(c.repack_sphere_budget > 0 && c.repack_sphere_budget <= 8))
    throw InputError(s.file, "cutting.repack_sphere_budget", "must lie in (0, 8]");
}

}  // namespace

void checkDissectionScene(const CompiledScene& scene) {
  const std::string& f = scene.file;
  if (!scene.models.cutting) throw InputError(f, "models.cutting", "the dissection model needs cutting: true");
  if (!scene.models.pbd_metaballs) throw InputError(f, "models.pbd_metaballs", "cutting needs the PBD metaball organ");
  if (scene.pbd.iterations < 1) throw InputError(f, "pbd.iterations", "must be >= 1");
  checkCuttingRanges(scene);
}

void checkStrokesApart(const std::string& f, const std::vector<ScriptedStroke>& strokes) {
  for (std::size_t k = 1; k < strokes.size(); ++k)
    if (strokes[k].start < strokes[k - 1].end)
      throw InputError(f, "tools",
                       "scalpel \"" + strokes[k].tool.name + "\" starts at t = " + std::to_string(strokes[k].start) +
                           " s, before scalpel \"" + strokes[k - 1].tool.name + "\" leaves the tissue at t = " +
                           std::to_string(strokes[k - 1].end) + " s: strokes must not overlap");
}

void checkFixedMlsSubsteps(const CompiledScene& scene, const MetaballModel& spheres, const MlsMaterial& material) {
  const int fixed = scene.cutting.mls_substeps_per_exchange;
  if (fixed <= 0) return;
  double rmin = std::numeric_limits<double>::infinity();
  for (double r : spheres.rest_radii) rmin = std::min(rmin, r);
  const double spacing = 2.0 * rmin / scene.cutting.samples_per_diameter;
  const MlsCoefficients<double> c = mlsCoefficients(material);
  const double stable = mlsStableTimeStep(c.mu, c.lambda, c.k_volume, scene.material.density_kg_m3, spacing);
  const double dt = scene.solver.frame_dt / scene.cutting.exchanges_per_frame / fixed;
  if (dt > stable)
    throw InputError(
        scene.file, "cutting.mls_substeps_per_exchange",
        std::to_string(fixed) + " substeps give dt = " + std::to_string(dt) +
            " s, above the nodal points' stable step " + std::to_string(stable) + " s (needs at least " +
            std::to_string(int(std::ceil(scene.solver.frame_dt / scene.cutting.exchanges_per_frame / stable))) +
            "); use more, or 0 to choose automatically");
}

}  // namespace inc::dissection
