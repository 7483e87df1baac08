// Frame loop of `incision run`: advance, guard (rollback + one retry), metrics, periodic and final outputs.
#include "host/app/runner.h"
#include "host/scene/scene_compile.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <thread>

#include "base/format_number.h"
#include "base/progress.h"
#include "host/app/memory_estimate.h"
#include "host/app/metrics_csv.h"
#include "host/backends/backend_choice.h"
#include "host/haptics/haptic_scene_model.h"
#include "host/io/point_io.h"
#include "host/sim/numerical_guard.h"
#include "model/input_error.h"

namespace inc {
namespace fs = std::filesystem;

namespace {

double sceneEnergyFloor(const Scene& scene, const std::vector<Vec3d>& positions) {
  // m |g| L with m ~ density * bounding-box volume: an energy no sane scene reaches by a factor of
  // energy_bound, so that a body starting at rest still has a meaningful blow-up bound.
  if (positions.empty()) return 1e-12;
  Vec3d lo = positions[0], hi = positions[0];
  for (const auto& p : positions)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  const Vec3d ext = hi - lo;
  const double L = std::max(norm(ext), 1e-6);
  const double vol = std::max(ext.x, 1e-3 * L) * std::max(ext.y, 1e-3 * L) * std::max(ext.z, 1e-3 * L);
  const double g = std::max(norm(scene.solver.gravity), 1.0);
  return scene.material.density_kg_m3 * vol * g * L;
}

void writeState(const std::vector<std::unique_ptr<SimulationModel>>& models, const Scene& scene, const fs::path& dir,
                const std::string& stem) {
  std::vector<Vec3d> pts;
  TriangleMesh surface;
  for (const auto& m : models) {
    const std::string base = (dir / (stem + "_" + m->name())).string();
    m->currentPositions(pts);
    if (scene.output.particles_ply) writePointsPly(base + "_particles.ply", pts);
    if (scene.output.vtk) writePointsVtk(base + "_particles.vtk", pts);
    if (m->currentSurface(surface)) {
      if (scene.output.mesh_obj) writeObj(base + "_surface.obj", surface);
      if (scene.output.vtk) writeMeshVtk(base + "_surface.vtk", surface);
    }
  }
}

std::string describe(long frame, const GuardVerdict& v) {
  std::ostringstream s;
  s << "frame " << frame << ", stage '" << v.stage << "'";
  if (v.particle >= 0) s << ", particle " << v.particle;
  s << ": " << v.reason;
  return s.str();
}

// The scene with the command line's backend and precision overrides; rejects bad run lengths.
Scene sceneForRun(const Scene& scene_in, const RunOptions& opt) {
  Scene scene = scene_in;
  if (opt.backend) scene.solver.backend = *opt.backend;
  if (opt.precision) scene.solver.precision = *opt.precision;
  if (opt.frames && !(*opt.frames >= 1 && *opt.frames <= kMaxRunFrames))
    throw InputError("", "--steps",
                     "must be a number of frames in [1, " + std::to_string(kMaxRunFrames) + "] (got " +
                         std::to_string(*opt.frames) + ")");
  if (opt.seconds && !(*opt.seconds > 0.0 && std::isfinite(*opt.seconds)))
    throw InputError("", "--seconds",
                     "must be a positive, finite number of seconds (got " + formatNumber(*opt.seconds) + ")");
  if (opt.seconds && *opt.seconds / scene.solver.frame_dt > double(kMaxRunFrames))
    throw InputError("", "--seconds",
                     formatNumber(*opt.seconds) + " s is more than " + std::to_string(kMaxRunFrames) +
                         " frames of solver.frame_dt_s = " + formatNumber(scene.solver.frame_dt) + " s");
  if (!opt.frames && !opt.seconds && !(scene.duration / scene.solver.frame_dt <= double(kMaxRunFrames)))
    throw InputError(scene.file, "duration_s",
                     formatNumber(scene.duration) + " s is more than " + std::to_string(kMaxRunFrames) +
                         " frames of solver.frame_dt_s = " + formatNumber(scene.solver.frame_dt) +
                         " s: a run that long does not end");
  return scene;
}

// --steps, else --seconds, else the scene's duration, in frames of frame_dt (at least one).
long framesRequested(const Scene& scene, const RunOptions& opt) {
  const double dt = scene.solver.frame_dt;
  const double seconds = opt.seconds ? *opt.seconds : scene.duration;
  return opt.frames ? *opt.frames : std::max(1L, long(std::llround(seconds / dt)));
}

fs::path createOutputFolder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir, "--out", "cannot create the output folder: " + ec.message());
  return fs::path(dir);
}

// The guards' shared energy floor, summed over the models; each model's start is its first checkpoint.
double energyFloorAndCheckpoint(const std::vector<std::unique_ptr<SimulationModel>>& models, const Scene& scene) {
  std::vector<Vec3d> pts;
  double floor = 0.0;
  for (const auto& m : models) {
    m->currentPositions(pts);
    floor += sceneEnergyFloor(scene, pts);
    m->saveCheckpoint();
  }
  return floor;
}

// Why a failed frame is not retried ("" when it is): the model refused it, or the run's retries are spent.
std::string noRetryReason(const GuardVerdict& v, const RunOptions& opt, const RunSummary& sum) {
  if (!opt.retry_once) return "";
  if (!v.retryable) return " (not retried: a smaller step needs more substeps)";
  if (sum.retries >= kMaxGuardRetries)
    return " (not retried: the guard already halved the step " + std::to_string(sum.retries) +
           " times in this run, the most it does)";
  return "";
}

// Advances model k by one frame under its guard. A failed check rolls back and retries once with half the step
// (at most kMaxGuardRetries times a run, never a refused frame); a model that still fails is restored to its last
// good state and the failure goes into `sum`. Metrics are written for the first model, and for a failing one.
void advanceGuarded(SimulationModel& m, NumericalGuard& guard, std::size_t k, long f, double dt, const RunOptions& opt,
                    MetricsCsv* csv, RunSummary& sum) {
  const auto fs0 = std::chrono::steady_clock::now();
  FrameReport r = m.advance(dt);
  GuardVerdict v = guard.check(r);
  std::string not_retried = v.ok ? "" : noRetryReason(v, opt, sum);
  if (!v.ok && opt.retry_once && not_retried.empty()) {
    // Roll back to the last good state and retry once with half the step.
    if (!opt.quiet)
      std::fprintf(stderr, "\nguard: %s; rolling back and retrying with half the step\n", describe(f, v).c_str());
    m.restoreCheckpoint();
    m.scaleTimeStep(0.5);
    ++sum.retries;
    r = m.advance(dt);
    v = guard.check(r);
    if (!v.ok && !v.retryable) not_retried = " (after one retry at half the step)";
  }
  const double wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - fs0).count();
  if (!v.ok) {
    sum.failed = true;
    sum.failure = "model " + m.name() + ", " + describe(f, v) + not_retried;
    m.restoreCheckpoint();  // the last good state is what goes to disk
    if (csv) csv->write(f, double(f) * dt, wall_ms, r);
    return;
  }
  m.saveCheckpoint();
  sum.total_substeps += r.substeps;
  sum.max_displacement = std::max(sum.max_displacement, r.max_displacement);
  sum.final_total_energy = r.kinetic_energy + r.elastic_energy + r.potential_energy;
  if (csv && k == 0) csv->write(f, double(f) * dt, wall_ms, r);
}

// The frame loop: every model advances each frame until one fails; periodic states go to `out`. Sets the frames
// done and the wall time in `sum`.
void runFrames(const std::vector<std::unique_ptr<SimulationModel>>& models, std::vector<NumericalGuard>& guards,
               const Scene& scene, const RunOptions& opt, const fs::path& out, MetricsCsv* csv, bool paced,
               Progress& progress, RunSummary& sum) {
  const double dt = scene.solver.frame_dt;
  const auto t0 = std::chrono::steady_clock::now();
  for (long f = 1; f <= sum.frames_requested && !sum.failed; ++f) {
    // A haptics run is real time: the device moves in wall time, so frame f starts no earlier than (f - 1) dt.
    if (paced)
      std::this_thread::sleep_until(t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                             std::chrono::duration<double>(double(f - 1) * dt)));
    for (std::size_t k = 0; k < models.size() && !sum.failed; ++k)
      advanceGuarded(*models[k], guards[k], k, f, dt, opt, csv, sum);
    if (sum.failed) break;
    sum.frames_done = f;
    if (scene.output.every_frames > 0 && f % scene.output.every_frames == 0) {
      char stem[32];
      std::snprintf(stem, sizeof stem, "frame_%06ld", f);
      writeState(models, scene, out, stem);
    }
    progress.update(f);
  }
  sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Stops the haptic loop and keeps its statistics, recordings and the global model's final surface.
void finishHaptics(HapticSceneModel& haptic, const Scene& scene, const fs::path& out, RunSummary& sum) {
  SceneHaptics& h = haptic.haptics();
  h.stop();
  sum.haptic = h.summary();
  for (std::size_t k = 0; k < h.handCount(); ++k) sum.haptic_stats.push_back(h.stats(k));
  if (scene.haptics.record_trajectory) (void)h.writeRecordings(out.string());
  // The global model's organ, displaced by its last step (the tools' loads at the end of the run).
  if (h.globalModel() && scene.output.mesh_obj)
    writeObj((out / "final_haptic_organ_surface.obj").string(), h.globalModel()->deformedMesh());
}

void writeSummaryFile(const fs::path& out, const RunSummary& sum) {
  std::FILE* s = std::fopen((out / "summary.txt").string().c_str(), "w");
  if (s) {
    std::fprintf(s, "%s\n", sum.line().c_str());
    std::fclose(s);
  }
}

}  // namespace

std::string RunSummary::line() const {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(3);
  s << (failed ? "FAILED " : "done ") << frames_done << "/" << frames_requested << " frames (" << simulated_s
    << " s simulated, " << total_substeps << " substeps) in " << wall_s << " s wall, "
    << (wall_s > 0 ? double(frames_done) / wall_s : 0.0) << " frames/s; models: " << model_names
    << (build_notes.empty() ? "" : "; built: " + build_notes) << "; " << backend_note << "; max displacement "
    << std::scientific << std::setprecision(3) << max_displacement << " m; energy " << final_total_energy
    << " J; memory host " << std::fixed << std::setprecision(1) << double(memory.host_bytes) / 1048576.0
    << " MiB, device " << double(memory.device_bytes) / 1048576.0 << " MiB; retries " << retries;
  if (!haptic.empty()) s << "; " << haptic;
  if (failed) s << "; " << failure;
  return s.str();
}

long parseRunSteps(const std::string& text) {
  const std::string why =
      "must be a number of frames in [1, " + std::to_string(kMaxRunFrames) + "] (got \"" + text + "\")";
  if (text.empty() || text.size() > 9 || text.find_first_not_of("0123456789") != std::string::npos)
    throw InputError("", "--steps", why);
  const long frames = std::stol(text);
  if (frames < 1 || frames > kMaxRunFrames) throw InputError("", "--steps", why);
  return frames;
}

double parseRunSeconds(const std::string& text) {
  const std::string why = "must be a positive, finite number of seconds (got \"" + text + "\")";
  std::size_t used = 0;
  double seconds = 0;
  try {
    seconds = std::stod(text, &used);
  } catch (const std::exception&) {
    throw InputError("", "--seconds", why);
  }
  if (used != text.size() || !(seconds > 0.0 && std::isfinite(seconds))) throw InputError("", "--seconds", why);
  return seconds;
}

RunSummary runScene(const Scene& scene_in, const RunOptions& opt, const ModelFactory& factory) {
  const Scene scene = sceneForRun(scene_in, opt);
  RunSummary sum;
  const double dt = scene.solver.frame_dt;
  sum.frames_requested = framesRequested(scene, opt);
  const fs::path out = createOutputFolder(opt.out_dir);

  const BackendChoice choice = resolveBackend(scene.solver.backend);
  sum.backend_note = choice.note;
  if (!opt.quiet) std::fprintf(stderr, "%s\n", choice.note.c_str());
  if (!opt.quiet)
    for (const std::string& c : scene.chosen_settings) std::fprintf(stderr, "chosen: %s\n", c.c_str());
  if (!opt.quiet)
    for (const std::string& n : scene.notes) std::fprintf(stderr, "note: %s\n", n.c_str());

  // Before anything is sampled or allocated: refuse a scene that will not fit (host/app/memory_estimate.h).
  checkSceneMemory(scene, choice.kind, opt.memory_budget ? *opt.memory_budget : machineMemoryBudget(choice));
  const CompiledScene compiled = compileScene(scene);
  auto models = factory(compiled, choice.kind);
  if (models.empty()) throw InputError(scene.file, "models", "the scene switches on no model that can run");
  for (const auto& m : models) {
    sum.model_names += (sum.model_names.empty() ? "" : "+") + m->name();
    // How each model was built that a user should know of: its sphere fill, stragglers linked or dropped.
    if (const std::string note = m->buildNote(); !note.empty()) {
      sum.build_notes += (sum.build_notes.empty() ? "" : "; ") + m->name() + ": " + note;
      if (!opt.quiet) std::fprintf(stderr, "%s: %s\n", m->name().c_str(), note.c_str());
    } else if (!opt.quiet) {
      std::fprintf(stderr, "%s: %zu particles\n", m->name().c_str(), m->particleCount());
    }
  }
  // models.haptics: the haptic loop starts on its own thread beside this one (docs/haptics.md); none otherwise.
  SceneHapticsOptions haptic_options;
  haptic_options.record_s = std::min(600.0, 1.5 * double(sum.frames_requested) * dt + 5.0);
  haptic_options.quiet = opt.quiet;
  HapticSceneModel* haptic = attachSceneHaptics(models, compiled, haptic_options);

  const double floor = energyFloorAndCheckpoint(models, scene);
  std::vector<NumericalGuard> guards(models.size(), NumericalGuard(scene.solver.energy_bound, floor));
  std::unique_ptr<MetricsCsv> csv;
  if (scene.output.metrics_csv) csv = std::make_unique<MetricsCsv>((out / "metrics.csv").string());

  Progress progress("incision run " + scene.name, sum.frames_requested, opt.quiet);
  runFrames(models, guards, scene, opt, out, csv.get(), haptic != nullptr, progress, sum);
  if (haptic) finishHaptics(*haptic, scene, out, sum);
  sum.simulated_s = double(sum.frames_done) * dt;
  progress.finish(sum.failed ? "stopped" : "");
  for (const auto& m : models) {
    const MemoryReport mr = m->memory();
    sum.memory.host_bytes += mr.host_bytes;
    sum.memory.device_bytes += mr.device_bytes;
  }
  writeState(models, scene, out, sum.failed ? "last_good" : "final");
  writeSummaryFile(out, sum);
  return sum;
}

}  // namespace inc
