// The speed/accuracy trade of a scene: sweeps each model's knobs, measures ms per frame and the error against a
// reference.
#pragma once

#include <string>
#include <vector>

#include "host/app/tradeoff_analytic.h"
#include "host/scene/scene.h"
#include "model/backend.h"

namespace inc {

struct TradeoffOptions {
  std::vector<double> budgets_ms{1.0, 16.0};  // Pareto tables: settings whose ms per frame fit each budget
  BackendKind backend = BackendKind::Cpu;     // Auto resolves like the runner (CUDA when usable)
  bool quick = false;                         // fewer settings, shorter runs (CI: checks it runs, not accuracy)
  // The cost the Pareto tables and the plot use: false = wall time, true = CPU time of the process (on a
  // shared machine wall time also measures the neighbours; with OMP_NUM_THREADS=1 CPU time is one core's).
  bool cpu_cost = false;
};

// One measured setting. `knob` is "baseline" for the scene's own settings.
struct TradeoffRow {
  std::string model;  // "mls" | "pbd" | "mfs" (the haptic local model)
  // mls: "spacing" | "support_factor" | "safety" | "precision"; pbd: "iterations" | "substeps" | "spheres"
  // (lattice spacing) | "target_spheres" (the packer) | "precision"; mfs: "nodes"; all: "baseline"
  std::string knob;
  std::string value;  // the knob's value as text (spheres, nodes: the count built; target_spheres: the count asked)
  std::size_t particles = 0;  // particles / spheres / MFS nodes
  // The cost: wall_ms, or cpu_ms with TradeoffOptions::cpu_cost.
  double ms_per_frame = 0.0;
  // mls, pbd: medians over the timed frames of one advance(frame_dt) (wall: host clock, includes GPU sync;
  // cpu: CPU time of the whole process, all threads). mfs: the same for one haptic tick (eq. 6 condensed force).
  double wall_ms = 0.0, cpu_ms = 0.0;
  double setup_s = 0.0;     // building the model (sampling or packing, neighbourhoods; mfs: assembly + condensation)
  double observable = 0.0;  // in `unit`: tip deflection / tip drop / centroid displacement (m), punch force (N)
  std::string unit = "m";
  double error = 0.0;  // |observable - reference| / |reference|
  bool finite = true;
  // false: no particle (sphere centre) lay in the scene's fixed boxes, so the body fell: the setting changed
  // the problem, not its accuracy. Kept in the table, never Pareto-optimal.
  bool held = true;
  std::string note;  // refusal / failure / not-held text, empty when the run completed normally
};

struct TradeoffResult {
  std::string scene;
  std::string backend;
  std::string cost = "wall";  // "wall" | "cpu": what ms_per_frame holds
  // Per model: what the error is measured against ("Euler-Bernoulli cantilever tip deflection 6.5 mm", ...)
  std::vector<std::string> references;
  std::vector<TradeoffRow> rows;
};

// The cost name of the options for reports: "wall" or "cpu".
std::string tradeoffCostName(const TradeoffOptions& options);

// Sweeps one knob at a time around the scene's settings for each model the scene switches on (MLS, PBD and,
// with models.haptics, the MFS local model; MLS and PBD: the scene is copied with only that model on and built
// through createSceneModels). References: for MLS the analytic answer when detectAnalyticCase finds one
// (cantilever: Euler-Bernoulli; hanging bar: uniaxial stress), for PBD and otherwise a float64 run at the
// finest setting of the sweep; for MFS the flat punch force 2 a E delta / (1 - nu^2) (a: the radius of the
// scene's first probe or grasper, else 5 mm; the scene's E and nu). Throws InputError for a scene with none
// of these models, or bad options.
TradeoffResult runTradeoff(const Scene& scene, const TradeoffOptions& options);

// One setting of a sweep: the knob, its value as text and the scene that runs it.
struct TradeoffSetting {
  std::string knob, value;
  Scene scene;
};

// The settings swept for `model` ("mls" | "pbd") around `base`, one knob at a time, the baseline first.
// PBD sphere count: a lattice organ (pbd.target_spheres = 0) sweeps both the lattice spacing ("spheres") and
// the packer ("target_spheres" at 1/8 ... 1 of its lattice count); a packed organ sweeps only the packer
// (1/4, 1/2, 2 of its target). --quick: one value per knob.
std::vector<TradeoffSetting> tradeoffSettings(const Scene& base, const std::string& model, bool quick);

// The float64 run at the finest setting of the sweep, the reference where no analytic answer exists: half the
// spacing (a packed organ: twice the target spheres), MLS safety 0.1, PBD 40 iterations x 16 substeps
// (--quick: the scene's resolution, 10 x 4).
Scene tradeoffReferenceScene(const Scene& base, const std::string& model, bool quick);

// Indices of the rows that are Pareto-optimal (no other finite, held row is both faster and more accurate)
// among the finite, held rows with ms_per_frame <= budget_ms, sorted by ms. Call it with the rows of one model.
std::vector<std::size_t> paretoFront(const std::vector<TradeoffRow>& rows, double budget_ms);

std::string tradeoffCsv(const TradeoffResult& r);
// The markdown report: references, a table of the Pareto-optimal settings per budget, the full table.
std::string tradeoffMarkdown(const TradeoffResult& r, const std::vector<double>& budgets_ms);

// Parses "1,16" into budgets in ms; throws InputError(--budget-ms) for anything else.
std::vector<double> parseBudgets(const std::string& text);

}  // namespace inc
