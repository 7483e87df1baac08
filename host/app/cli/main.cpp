// The `incision` command line: run, validate, devices (and the subcommands of later modules).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>

#include "host/app/cli/tradeoff_command.h"
#include "host/app/cli/view_command.h"
#include "host/app/memory_estimate.h"
#include "host/app/runner.h"
#include "host/scene/embedded_scenes.h"
#include "host/scene/haptics_scene.h"
#include "host/scene/scene_loader.h"
#include "kernels/device_info.h"
#include "model/backend.h"
#include "model/input_error.h"

namespace {

// A scene argument is a file path, or the name of an embedded scene, or empty for the default.
inc::Scene resolveScene(const std::string& arg) {
  if (arg.empty()) {
    const auto& d = inc::defaultEmbeddedScene();
    return inc::parseScene(d.json, std::string("<embedded:") + d.name + ">", ".");
  }
  if (!std::filesystem::exists(arg)) {
    if (const auto* e = inc::findEmbeddedScene(arg))
      return inc::parseScene(e->json, std::string("<embedded:") + e->name + ">", ".");
  }
  return inc::loadSceneFile(arg);
}

int cmdDevices() {
  const auto d = inc::cuda::queryDevices();
  std::printf("CUDA backend compiled: %s\n", d.compiled ? "yes" : "no");
  if (d.device_count == 0) {
    std::printf("usable GPU: none (%s)\n", d.error.c_str());
  } else {
    std::printf("usable GPUs: %d; device 0: %s, sm_%d%d, %d SMs, %.1f GiB, peak %.0f GB/s\n", d.device_count,
                d.name.c_str(), d.sm_major, d.sm_minor, d.multiprocessors, double(d.global_memory_bytes) / (1 << 30),
                d.peak_bandwidth_gbs);
  }
  // Haptic device drivers (scene key haptics.device; docs/haptics.md).
  std::printf("haptic devices: scripted, udp (127.0.0.1), pointer (the viewer's mouse)%s\n",
              inc::openHapticsBuilt() ? ", openhaptics" : "");
  std::printf("OpenHaptics driver: %s\n",
              inc::openHapticsBuilt() ? "built (Phantom / Geomagic Touch through the HD API; untested here)"
                                      : "not built (CMake did not find the OpenHaptics SDK: HD/hd.h and libHD)");
  return 0;
}

int cmdScenes() {
  for (const auto& e : inc::embeddedScenes())
    std::printf("%-16s %s%s\n", e.name, e.summary,
                std::string(e.name) == inc::defaultEmbeddedScene().name ? " (default)" : "");
  return 0;
}

struct RunArgs {
  std::string scene, backend, precision, out_dir = "out";
  std::string steps, seconds;  // parsed by parseRunSteps / parseRunSeconds (strict: no silent clamping)
  bool quiet = false;
};

CLI::App* addRunCommand(CLI::App& app, RunArgs& a) {
  auto* run = app.add_subcommand("run", "Run a scene headless and write its outputs");
  run->add_option("scene", a.scene, "Scene file (JSON) or embedded scene name; default: the embedded default");
  auto* o_steps = run->add_option("--steps", a.steps, "Number of frames to run");
  run->add_option("--seconds", a.seconds, "Simulated seconds to run")->excludes(o_steps);
  run->add_option("--backend", a.backend, "auto | cuda | cpu (overrides the scene)");
  run->add_option("--precision", a.precision, "float32 | float64 (overrides the scene)");
  run->add_option("--out", a.out_dir, "Output folder (PLY/OBJ/VTK, metrics.csv, summary.txt)");
  run->add_flag("--quiet", a.quiet, "No progress output");
  return run;
}

int cmdRun(const RunArgs& a) {
  const inc::Scene scene = resolveScene(a.scene);
  inc::RunOptions opt;
  if (!a.steps.empty()) opt.frames = inc::parseRunSteps(a.steps);
  if (!a.seconds.empty()) opt.seconds = inc::parseRunSeconds(a.seconds);
  opt.out_dir = a.out_dir;
  opt.quiet = a.quiet;
  if (!a.backend.empty()) opt.backend = inc::parseBackend(a.backend);
  if (!a.precision.empty()) {
    if (a.precision == "float32")
      opt.precision = inc::Precision::Float32;
    else if (a.precision == "float64")
      opt.precision = inc::Precision::Float64;
    else
      throw inc::InputError("", "--precision", "unknown precision '" + a.precision + "' (float32 or float64)");
  }
  const inc::RunSummary sum = inc::runScene(scene, opt);
  std::printf("incision: %s: %s\n", scene.name.c_str(), sum.line().c_str());
  std::printf("incision: outputs in %s\n", a.out_dir.c_str());
  return sum.failed ? inc::kExitSimulationFailed : 0;
}

struct ViewArgs {
  std::string scene, backend, screenshot, camera;
  int frames = 0;
  bool splats = false;
};

CLI::App* addViewCommand(CLI::App& app, ViewArgs& a) {
  auto* view = app.add_subcommand("view", "Show a scene in the interactive viewer (GLFW + Dear ImGui)");
  view->add_option("scene", a.scene, "Scene file (JSON) or embedded scene name; default: the embedded default");
  view->add_option("--backend", a.backend, "auto | cuda | cpu (overrides the scene)");
  view->add_option("--frames", a.frames, "Scripted run: draw N frames, then exit")->check(CLI::NonNegativeNumber);
  view->add_option("--screenshot", a.screenshot, "PNG written after the last scripted frame");
  view->add_flag("--splats", a.splats, "Start with point splats instead of the shaded surface");
  view->add_option("--camera", a.camera,
                   "First view: YAW,PITCH[,DISTANCE] (degrees about the up axis, degrees above the horizontal, metres "
                   "from the framed centre; default: the framing's)");
  return view;
}

int cmdView(const ViewArgs& a) {
  inc::cli::ViewCommandOptions vo;
  if (!a.backend.empty()) vo.backend = inc::parseBackend(a.backend);
  vo.frames = a.frames;
  vo.screenshot = a.screenshot;
  vo.splats = a.splats;
  if (!a.camera.empty()) vo.camera = inc::parseCameraAngles(a.camera);
  return inc::cli::runViewCommand(resolveScene(a.scene), vo);
}

struct TradeoffArgs {
  std::string scene, budgets = "1,16", out_dir = "tradeoff", backend, models, cost = "wall";
  bool quick = false;
};

CLI::App* addTradeoffCommand(CLI::App& app, TradeoffArgs& a) {
  auto* tradeoff =
      app.add_subcommand("tradeoff", "Sweep the scene's model knobs: ms per frame vs error (CSV, table, plot)");
  tradeoff->add_option("scene", a.scene,
                       "Scene file (JSON) or embedded scene name; default: the embedded beam (analytic reference)");
  tradeoff->add_option("--budget-ms", a.budgets, "Comma list of frame budgets in ms for the Pareto tables");
  tradeoff->add_option("--out", a.out_dir, "Output folder (tradeoff.csv, tradeoff.md, tradeoff.png)");
  tradeoff->add_option("--backend", a.backend, "auto | cuda | cpu (default cpu)");
  tradeoff->add_option("--models", a.models, "Comma list (mls,pbd,mfs) swept instead of the scene's models");
  tradeoff->add_flag("--quick", a.quick, "Few settings, short runs (checks it runs)");
  tradeoff->add_option("--cost", a.cost, "wall | cpu: the time the Pareto tables use (cpu: process CPU time)");
  return tradeoff;
}

int cmdTradeoff(const TradeoffArgs& a) {
  inc::cli::TradeoffCommandOptions to;
  to.sweep.budgets_ms = inc::parseBudgets(a.budgets);
  to.sweep.quick = a.quick;
  if (!a.backend.empty()) to.sweep.backend = inc::parseBackend(a.backend);
  to.out_dir = a.out_dir;
  to.models = a.models;
  to.cost = a.cost;
  return inc::cli::runTradeoffCommand(resolveScene(a.scene.empty() ? "beam" : a.scene), to);
}

int cmdValidate(const std::string& path) {
  const inc::Scene s = inc::loadSceneFile(path);
  // The memory check `run` makes before it builds anything, against the backend the scene asks for (a GPU that is
  // not there leaves the host check alone: `run` says so).
  inc::BackendChoice choice;
  if (s.solver.backend != inc::BackendKind::Cpu) {
    try {
      choice = inc::resolveBackend(s.solver.backend);
    } catch (const inc::InputError&) {
    }
  }
  const inc::SceneMemoryEstimate e = inc::checkSceneMemory(s, choice.kind, inc::machineMemoryBudget(choice));
  std::printf("%s: ok (%s)\n", path.c_str(), s.name.c_str());
  for (const std::string& c : s.chosen_settings) std::printf("chosen: %s\n", c.c_str());
  for (const std::string& n : s.notes) std::printf("note: %s\n", n.c_str());
  std::printf("memory estimate: %.1f MiB host, %.1f MiB device (%s)\n", double(e.bytes.host_bytes) / 1048576.0,
              double(e.bytes.device_bytes) / 1048576.0, e.detail.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Incision: GPU-first soft-tissue simulation for surgical training"};
  app.require_subcommand(1);

  RunArgs run_args;
  auto* run = addRunCommand(app, run_args);
  ViewArgs view_args;
  auto* view = addViewCommand(app, view_args);
  std::string validate_arg;
  auto* validate = app.add_subcommand("validate", "Load and check a scene file; print what it switches on");
  validate->add_option("scene", validate_arg, "Scene file (JSON)")->required();
  auto* scenes = app.add_subcommand("scenes", "List the embedded scenes");
  auto* devices = app.add_subcommand("devices", "Report the CUDA devices and haptic device drivers this build can use");
  TradeoffArgs tradeoff_args;
  auto* tradeoff = addTradeoffCommand(app, tradeoff_args);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : inc::kExitBadInput;
  }

  try {
    if (*devices) return cmdDevices();
    if (*scenes) return cmdScenes();
    if (*validate) return cmdValidate(validate_arg);
    if (*view) return cmdView(view_args);
    if (*tradeoff) return cmdTradeoff(tradeoff_args);
    if (*run) return cmdRun(run_args);
  } catch (const inc::InputError& e) {
    std::fprintf(stderr, "incision: error: %s\n", e.what());
    return inc::kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "incision: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
