// The headless runner: runs a scene frame by frame with the numerical guard, metrics and outputs.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "host/app/memory_estimate.h"
#include "host/haptics/haptic_loop.h"
#include "host/scene/scene.h"
#include "host/sim/model_factory.h"
#include "host/sim/simulation_model.h"

namespace inc {

// The longest run the runner accepts, in frames (19 days of simulated time at 60 Hz): a larger --steps, or a
// --seconds that needs more frames, is a typing mistake, refused instead of running until killed.
inline constexpr long kMaxRunFrames = 100000000;

// The guard's retries per run: each rolls a failed frame back and halves the time step for the rest of the run, so
// the step ends at 1/8 of the scene's at most; the next failure ends the run (exit 3). Together with the frame
// budget (model/frame_budget.h) and the frame count this bounds a run's work.
inline constexpr int kMaxGuardRetries = 3;

struct RunOptions {
  std::optional<long> frames;          // --steps N: frames of scene.solver.frame_dt, [1, kMaxRunFrames]
  std::optional<double> seconds;       // --seconds T: simulated seconds, > 0 (neither: the scene's duration)
  std::optional<BackendKind> backend;  // --backend overrides the scene
  std::optional<Precision> precision;  // --precision overrides the scene
  std::string out_dir = "out";
  bool quiet = false;
  std::optional<MemoryBudget> memory_budget;  // the memory check's budget (tests); default: machineMemoryBudget
  bool retry_once = true;  // guard: roll back and retry a failed frame once with half the step (kMaxGuardRetries)
};

struct RunSummary {
  long frames_requested = 0;
  long frames_done = 0;
  double simulated_s = 0.0;
  double wall_s = 0.0;
  long total_substeps = 0;
  int retries = 0;
  bool failed = false;
  std::string failure;  // which frame, stage, particle, why
  std::string backend_note;
  std::string model_names;
  std::string build_notes;  // each model's SimulationModel::buildNote, "name: note; ..." (empty: none had one)
  double max_displacement = 0.0;
  double final_total_energy = 0.0;
  MemoryReport memory;
  std::string haptic;  // a models.haptics scene: each haptic loop's statistics (SceneHaptics::summary)
  std::vector<PeriodStats> haptic_stats;  // ... and its period statistics, one per device (empty: no haptic loop)
  std::string line() const;               // the one-line summary printed at the end
};

// Creates the models the scene switches on (createSceneModels, host/sim/model_factory.h) or a test's own.
using ModelFactory = std::function<std::vector<std::unique_ptr<SimulationModel>>(const CompiledScene&, BackendKind)>;

// The text of --steps as a frame count: digits only, in [1, kMaxRunFrames]; else InputError("", "--steps", why).
long parseRunSteps(const std::string& text);
// The text of --seconds as simulated seconds: a finite number > 0; else InputError("", "--seconds", why).
double parseRunSeconds(const std::string& text);

// Runs the scene. Throws InputError for bad options (a frame count out of [1, kMaxRunFrames], seconds not > 0 or
// needing more than kMaxRunFrames frames); a numerical failure is returned in the summary
// (failed == true) after the last good state has been written to out_dir.
RunSummary runScene(const Scene& scene, const RunOptions& opt, const ModelFactory& factory = createSceneModels);

}  // namespace inc
