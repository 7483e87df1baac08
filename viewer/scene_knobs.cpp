// Material / Solver knobs over a shared, edited copy of the scene, and the model factory reading it.
#include "viewer/scene_knobs.h"

#include <algorithm>
#include <cmath>

#include "host/backends/backend_choice.h"
#include "model/backend.h"
#include "model/input_error.h"
#include "host/app/runner.h"

namespace inc::viewer {

SceneViewerSetup makeSceneViewerSetup(const Scene& scene_in, std::optional<BackendKind> backend) {
  SceneViewerSetup out;
  out.scene = std::make_shared<Scene>(scene_in);
  if (backend) out.scene->solver.backend = *backend;
  const BackendChoice first = resolveBackend(out.scene->solver.backend);
  out.backend_note = first.note;
  out.scene->solver.backend = first.kind;
  std::shared_ptr<Scene> sc = out.scene;
  out.factory = [sc]() -> std::unique_ptr<SimulationModel> {
    const BackendKind kind = resolveBackend(sc->solver.backend).kind;
    if (kind != sc->solver.backend) throw InputError(sc->file, "solver.backend", "the requested backend is not available here");
    auto models = createSceneModels(*sc, kind);
    if (models.empty()) throw InputError(sc->file, "models", "the scene switches on no model to show");
    return std::move(models.front());
  };

  auto knob = [&](const char* group, const char* label, double lo, double hi, double value, bool log, bool integer,
                  std::function<void(double)> edit) {
    ViewerKnob k;
    k.group = group;
    k.label = label;
    k.min_value = lo;
    k.max_value = hi;
    k.value = std::clamp(value, lo, hi);
    k.logarithmic = log;
    k.integer = integer;
    k.edit = std::move(edit);
    out.knobs.push_back(std::move(k));
  };
  const Scene& s = *sc;
  const double e = s.material.youngs_modulus > 0 ? s.material.youngs_modulus : 1.0e4;
  knob("Material", "Young's modulus [Pa]", e / 100.0, e * 100.0, e, true, false,
       [sc](double v) { sc->material.youngs_modulus = v; });
  if (s.models.mls)
    knob("Material", "Poisson ratio", 0.0, 0.49, s.material.poisson_ratio, false, false,
         [sc](double v) { sc->material.poisson_ratio = v; });
  if (s.models.pbd_metaballs || s.models.cutting) {
    knob("Solver", "PBD iterations", 1, 100, s.pbd.iterations, true, true,
         [sc](double v) { sc->pbd.iterations = int(std::lround(v)); });
    ViewerKnob k;
    k.group = "Solver";
    k.label = "PBD solver";
    k.choices = {"jacobi", "gauss_seidel"};
    k.value = s.pbd.solver == "gauss_seidel" ? 1 : 0;
    k.edit = [sc](double v) { sc->pbd.solver = v > 0.5 ? "gauss_seidel" : "jacobi"; };
    out.knobs.push_back(std::move(k));
    // Jacobi only: with Gauss-Seidel a non-zero value is refused (the rebuild is undone and says why).
    knob("Solver", "PBD Chebyshev rho (Jacobi)", 0.0, 0.9, s.pbd.chebyshev_rho, false, false,
         [sc](double v) { sc->pbd.chebyshev_rho = v; });
  }
  if (s.models.cutting) {
    // The stroke's end off the frame (0: the frame the blade leaves takes it all) and the blade as a contact.
    knob("Cutting", "stroke end delay [frames]", 0, 30, s.cutting.stroke_end_frames, false, true,
         [sc](double v) { sc->cutting.stroke_end_frames = int(std::lround(v)); });
    // Each conversion's rest-configuration work beside the frame, applied at the next one (0: in the frame).
    knob("Cutting", "conversion delay [frames]", 0, 1, s.cutting.conversion_delay_frames, false, true,
         [sc](double v) { sc->cutting.conversion_delay_frames = int(std::lround(v)); });
    // The surface opened along the sweep while the blade is in, every so many frames (0: when the stroke ends).
    knob("Cutting", "open surface every [frames]", 0, 30, s.cutting.open_surface_frames, false, true,
         [sc](double v) { sc->cutting.open_surface_frames = int(std::lround(v)); });
    knob("Cutting", "blade contact radius [m]", 0.0, 0.005, s.cutting.blade_radius_m, false, false,
         [sc](double v) { sc->cutting.blade_radius_m = v; });
    knob("Cutting", "blade friction", 0.0, 1.0, s.cutting.blade_friction, false, false,
         [sc](double v) { sc->cutting.blade_friction = v; });
  }
  knob("Solver", "substeps (0 = auto)", 0, 64, s.solver.substeps, false, true,
       [sc](double v) { sc->solver.substeps = int(std::lround(v)); });
  {
    ViewerKnob k;
    k.group = "Solver";
    k.label = "time step [s]";
    k.min_value = 1.0e-4;
    k.max_value = 0.05;
    k.value = std::clamp(s.solver.frame_dt, k.min_value, k.max_value);
    k.logarithmic = true;
    k.frame_dt = true;
    k.edit = [sc](double v) { sc->solver.frame_dt = v; };
    out.knobs.push_back(std::move(k));
  }
  {
    ViewerKnob k;
    k.group = "Solver";
    k.label = "precision";
    k.choices = {"float32", "float64"};
    k.value = s.solver.precision == Precision::Float64 ? 1 : 0;
    k.edit = [sc](double v) { sc->solver.precision = v > 0.5 ? Precision::Float64 : Precision::Float32; };
    out.knobs.push_back(std::move(k));
  }
  {
    ViewerKnob k;
    k.group = "Solver";
    k.label = "backend";
    k.choices = {"cpu"};
#if INCISION_HAVE_CUDA
    k.choices.push_back("cuda");
#endif
    k.value = s.solver.backend == BackendKind::Cuda && k.choices.size() > 1 ? 1 : 0;
    k.edit = [sc](double v) { sc->solver.backend = v > 0.5 ? BackendKind::Cuda : BackendKind::Cpu; };
    out.knobs.push_back(std::move(k));
  }
  return out;
}

}  // namespace inc::viewer
