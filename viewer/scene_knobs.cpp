// Material / Solver knobs over a shared, edited copy of the scene, and the model factory reading it.
#include "viewer/scene_knobs.h"
#include "host/scene/scene_compile.h"

#include <algorithm>
#include <cmath>

#include "host/app/runner.h"
#include "host/backends/backend_choice.h"
#include "model/backend.h"
#include "model/input_error.h"

namespace inc::viewer {

namespace {

using SceneEdit = std::function<void(double)>;

ViewerKnob sliderKnob(const char* group, const char* label, double lo, double hi, double value, bool log, bool integer,
                      SceneEdit edit) {
  ViewerKnob k;
  k.group = group;
  k.label = label;
  k.min_value = lo;
  k.max_value = hi;
  k.value = std::clamp(value, lo, hi);
  k.logarithmic = log;
  k.integer = integer;
  k.edit = std::move(edit);
  return k;
}

// A combo box; the value is the index of the chosen entry.
ViewerKnob choiceKnob(const char* group, const char* label, std::vector<std::string> choices, double value,
                      SceneEdit edit) {
  ViewerKnob k;
  k.group = group;
  k.label = label;
  k.choices = std::move(choices);
  k.value = value;
  k.edit = std::move(edit);
  return k;
}

// The scene's first model on the edited scene's backend; refuses a backend this build or machine lacks.
ModelFactory sceneModelFactory(std::shared_ptr<Scene> sc) {
  return [sc]() -> std::unique_ptr<SimulationModel> {
    const BackendKind kind = resolveBackend(sc->solver.backend).kind;
    if (kind != sc->solver.backend)
      throw InputError(sc->file, "solver.backend", "the requested backend is not available here");
    auto models = createSceneModels(compileScene(*sc), kind);
    if (models.empty()) throw InputError(sc->file, "models", "the scene switches on no model to show");
    return std::move(models.front());
  };
}

void addMaterialKnobs(const std::shared_ptr<Scene>& sc, std::vector<ViewerKnob>& out) {
  const Scene& s = *sc;
  const double e = s.material.youngs_modulus_pa > 0 ? s.material.youngs_modulus_pa : 1.0e4;
  out.push_back(sliderKnob("Material", "Young's modulus [Pa]", e / 100.0, e * 100.0, e, true, false,
                           [sc](double v) { sc->material.youngs_modulus_pa = v; }));
  if (s.models.mls)
    out.push_back(sliderKnob("Material", "Poisson ratio", 0.0, 0.49, s.material.poisson_ratio, false, false,
                             [sc](double v) { sc->material.poisson_ratio = v; }));
}

// PBD scenes (metaballs, cutting): iterations, Jacobi or Gauss-Seidel, Chebyshev acceleration.
void addPbdKnobs(const std::shared_ptr<Scene>& sc, std::vector<ViewerKnob>& out) {
  const Scene& s = *sc;
  if (!(s.models.pbd_metaballs || s.models.cutting)) return;
  out.push_back(sliderKnob("Solver", "PBD iterations", 1, 100, s.pbd.iterations, true, true,
                           [sc](double v) { sc->pbd.iterations = int(std::lround(v)); }));
  out.push_back(choiceKnob("Solver", "PBD solver", {"jacobi", "gauss_seidel"}, s.pbd.solver == "gauss_seidel" ? 1 : 0,
                           [sc](double v) { sc->pbd.solver = v > 0.5 ? "gauss_seidel" : "jacobi"; }));
  // Jacobi only: with Gauss-Seidel a non-zero value is refused (the rebuild is undone and says why).
  out.push_back(sliderKnob("Solver", "PBD Chebyshev rho (Jacobi)", 0.0, 0.9, s.pbd.chebyshev_rho, false, false,
                           [sc](double v) { sc->pbd.chebyshev_rho = v; }));
}

void addCuttingKnobs(const std::shared_ptr<Scene>& sc, std::vector<ViewerKnob>& out) {
  const Scene& s = *sc;
  if (!s.models.cutting) return;
  // The stroke's end off the frame (0: the frame the blade leaves takes it all) and the blade as a contact.
  out.push_back(sliderKnob("Cutting", "stroke end delay [frames]", 0, 30, s.cutting.stroke_end_frames, false, true,
                           [sc](double v) { sc->cutting.stroke_end_frames = int(std::lround(v)); }));
  // Each conversion's rest-configuration work beside the frame, applied at the next one (0: in the frame).
  out.push_back(sliderKnob("Cutting", "conversion delay [frames]", 0, 1, s.cutting.conversion_delay_frames, false, true,
                           [sc](double v) { sc->cutting.conversion_delay_frames = int(std::lround(v)); }));
  // The surface opened along the sweep while the blade is in, every so many frames (0: when the stroke ends).
  out.push_back(sliderKnob("Cutting", "open surface every [frames]", 0, 30, s.cutting.open_surface_frames, false, true,
                           [sc](double v) { sc->cutting.open_surface_frames = int(std::lround(v)); }));
  out.push_back(sliderKnob("Cutting", "blade contact radius [m]", 0.0, 0.005, s.cutting.blade_radius_m, false, false,
                           [sc](double v) { sc->cutting.blade_radius_m = v; }));
  out.push_back(sliderKnob("Cutting", "blade friction", 0.0, 1.0, s.cutting.blade_friction, false, false,
                           [sc](double v) { sc->cutting.blade_friction = v; }));
}

// Every scene: substeps, the time step (live, no rebuild), precision and backend.
void addSolverKnobs(const std::shared_ptr<Scene>& sc, std::vector<ViewerKnob>& out) {
  const Scene& s = *sc;
  out.push_back(sliderKnob("Solver", "substeps (0 = auto)", 0, 64, s.solver.substeps, false, true,
                           [sc](double v) { sc->solver.substeps = int(std::lround(v)); }));
  ViewerKnob dt = sliderKnob("Solver", "time step [s]", 1.0e-4, 0.05, s.solver.frame_dt, true, false,
                             [sc](double v) { sc->solver.frame_dt = v; });
  dt.frame_dt = true;
  out.push_back(std::move(dt));
  out.push_back(
      choiceKnob("Solver", "precision", {"float32", "float64"}, s.solver.precision == Precision::Float64 ? 1 : 0,
                 [sc](double v) { sc->solver.precision = v > 0.5 ? Precision::Float64 : Precision::Float32; }));
  std::vector<std::string> backends = {"cpu"};
#if INCISION_HAVE_CUDA
  backends.push_back("cuda");
#endif
  const double backend = s.solver.backend == BackendKind::Cuda && backends.size() > 1 ? 1 : 0;
  out.push_back(choiceKnob("Solver", "backend", std::move(backends), backend,
                           [sc](double v) { sc->solver.backend = v > 0.5 ? BackendKind::Cuda : BackendKind::Cpu; }));
}

}  // namespace

SceneViewerSetup makeSceneViewerSetup(const Scene& scene_in, std::optional<BackendKind> backend) {
  SceneViewerSetup out;
  out.scene = std::make_shared<Scene>(scene_in);
  if (backend) out.scene->solver.backend = *backend;
  const BackendChoice first = resolveBackend(out.scene->solver.backend);
  out.backend_note = first.note;
  out.scene->solver.backend = first.kind;
  out.factory = sceneModelFactory(out.scene);
  // The order is the panels' order (and the knobs' indices).
  addMaterialKnobs(out.scene, out.knobs);
  addPbdKnobs(out.scene, out.knobs);
  addCuttingKnobs(out.scene, out.knobs);
  addSolverKnobs(out.scene, out.knobs);
  return out;
}

}  // namespace inc::viewer
