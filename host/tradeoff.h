// The speed/accuracy trade of a scene: sweeps each model's knobs, measures ms per frame and the error against a reference.
#pragma once

#include <string>
#include <vector>

#include "host/backend.h"
#include "host/scene.h"

namespace inc {

struct TradeoffOptions {
  std::vector<double> budgets_ms{1.0, 16.0};  // Pareto tables: settings whose ms per frame fit each budget
  BackendKind backend = BackendKind::Cpu;     // Auto resolves like the runner (CUDA when usable)
  bool quick = false;                         // fewer settings, shorter runs (CI: checks it runs, not accuracy)
};

// One measured setting. `knob` is "baseline" for the scene's own settings.
struct TradeoffRow {
  std::string model;       // "mls" | "pbd"
  std::string knob;        // "spacing" | "support_factor" | "safety" | "precision" | "iterations" | "substeps" | "spheres" | "baseline"
  std::string value;       // the knob's value as text
  std::size_t particles = 0;
  double ms_per_frame = 0.0;   // median wall time of one advance(frame_dt) (host wall; includes GPU sync)
  double observable = 0.0;     // m: tip deflection (cantilever) or centroid displacement magnitude at the end
  double error = 0.0;          // |observable - reference| / |reference|
  bool finite = true;
  std::string note;            // refusal / failure text, empty when the run completed
};

struct TradeoffResult {
  std::string scene;
  std::string backend;
  // Per model: what the error is measured against ("Euler-Bernoulli cantilever tip deflection 6.5 mm", ...)
  std::vector<std::string> references;
  std::vector<TradeoffRow> rows;
};

// Sweeps one knob at a time around the scene's settings for each model the scene switches on (MLS and PBD;
// the scene is copied with only that model on and built through createSceneModels). Reference: the
// Euler-Bernoulli tip deflection when the body is a cantilever (beam or box clamped by one `fixed` box at its
// x-min end, gravity along -z); otherwise a float64 run at the finest setting of the sweep. Throws
// InputError for a scene without MLS or PBD, or bad options.
TradeoffResult runTradeoff(const Scene& scene, const TradeoffOptions& options);

// Indices of the rows that are Pareto-optimal (no other finite row is both faster and more accurate) among
// those with ms_per_frame <= budget_ms, sorted by ms.
std::vector<std::size_t> paretoFront(const std::vector<TradeoffRow>& rows, double budget_ms);

std::string tradeoffCsv(const TradeoffResult& r);
// The markdown report: references, a table of the Pareto-optimal settings per budget, the full table.
std::string tradeoffMarkdown(const TradeoffResult& r, const std::vector<double>& budgets_ms);

// Parses "1,16" into budgets in ms; throws InputError(--budget-ms) for anything else.
std::vector<double> parseBudgets(const std::string& text);

// The Euler-Bernoulli cantilever tip deflection q L^4 / (8 E I) under own weight (q = rho g b h,
// I = b h^3 / 12), in m. L free length, b width (y), h height (along gravity).
double eulerBernoulliTipDeflection(double length, double width, double height, double youngs, double density,
                                   double gravity);

}  // namespace inc
