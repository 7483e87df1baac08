// Runs a SimulationModel for the viewer, on its own thread (or stepped by the caller), and publishes
// snapshots; pause, single step, reset, slow motion and live parameter knobs are commands to it.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "host/io/mesh.h"
#include "host/sim/simulation_model.h"

namespace inc::viewer {

using ModelFactory = std::function<std::unique_ptr<SimulationModel>()>;

// A live parameter the UI shows as a slider (Young's modulus, iterations, substeps, ...). Values are clamped
// to [min, max]; all effects run on the simulation thread between frames. A knob has one or more of:
// - `apply`: changes the running model in place;
// - `edit`: changes the scene the factory builds from; the runner then rebuilds the model (camera and UI
//   kept, the state restarts from rest). When the rebuild throws, the old model stays, the edit is undone
//   with the previous value and the snapshot's `message` says why;
// - `frame_dt`: the value is the simulated time per frame (s), the runner's time step, applied live (its
//   `edit`, if any, also runs, without a rebuild: later rebuilds see the new time step).
struct ViewerKnob {
  std::string label;  // with units: "Young's modulus [Pa]"
  double min_value = 0.0;
  double max_value = 1.0;
  double value = 0.0;
  bool logarithmic = false;
  bool integer = false;
  std::function<void(SimulationModel&, double)> apply;
  std::function<void(double)> edit;
  bool frame_dt = false;
  std::vector<std::string> choices;  // non-empty: a combo box; value = index into choices
  std::string group;                 // panel header ("Material", "Solver"); empty: "Speed / accuracy"
};

struct SimSnapshot {
  std::uint64_t frame = 0;  // frames advanced since the start or the last reset
  double sim_time_s = 0.0;
  FrameReport report;       // of the last frame
  double advance_ms = 0.0;  // wall time of the last advance()
  std::vector<Vec3d> positions;
  TriangleMesh surface;
  bool has_surface = false;
  std::string name;
  BackendKind backend = BackendKind::Cpu;
  std::size_t particles = 0;
  bool failed = false;  // a frame was non-finite: the state was rolled back and the run paused
  std::string failure;
  ToolSupport tool_support;             // what the model's interactive tool can do
  ToolResult last_tool;                 // result of the last tool event applied
  std::vector<std::uint8_t> cut_walls;  // per surface triangle: 1 = cut wall (SimulationModel::cutWallTriangles)
  RenderLayers layers;                  // SimulationModel::renderLayers, while the viewer wants them (else empty)
  std::string message;                  // the last knob rebuild or tool error, empty when none
  std::uint64_t rebuilds = 0;           // models built by resets and scene edits
};

class SimRunner {
 public:
  // `model` may be null when `factory` is given (it builds the first model). threaded: the model advances
  // on a worker thread in real time (frame_dt_s of simulated time per frame_dt_s of wall time, times the
  // slow-motion scale) and never waits for drawing; otherwise pump() advances one frame per call.
  SimRunner(std::unique_ptr<SimulationModel> model, ModelFactory factory, std::vector<ViewerKnob> knobs,
            double frame_dt_s, bool threaded);
  ~SimRunner();
  SimRunner(const SimRunner&) = delete;
  SimRunner& operator=(const SimRunner&) = delete;

  void setPaused(bool paused);
  bool paused() const;
  void stepOnce();  // advance exactly one frame (while paused)
  bool canReset() const { return bool(factory_); }
  void reset();                     // rebuild from the factory; knobs are re-applied
  void setTimeScale(double scale);  // slow motion: simulated seconds per wall second, (0, 1]
  double timeScale() const;
  void setStepSafety(double factor);  // relative to the model's default; forwarded as scaleTimeStep ratios
  double stepSafety() const;
  void setKnob(std::size_t index, double value);
  std::vector<ViewerKnob> knobs() const;
  double frameDt() const;
  // The interactive tool: events are queued (UI thread) and applied in order at the start of the next frame
  // on the simulation thread (SimulationModel::applyTool). An event the model rejects (InputError) is
  // dropped and reported in the snapshot's `message`.
  void queueTool(const ToolEvent& event);
  // Whether snapshots carry the model's RenderLayers (spheres, forces, ...; collected only when shown).
  // Turning them on while paused republishes the current state at once.
  void setLayersWanted(bool wanted);

  void pump();  // synchronous mode: one frame unless paused (applies pending commands first)
  // Copies the newest snapshot when its version differs from `version` (and updates it); false otherwise.
  bool latest(SimSnapshot& out, std::uint64_t& version) const;
  // Blocks until the snapshot's frame count reaches `frame` or timeout_s passes (tests, scripted capture).
  bool waitForFrame(std::uint64_t frame, double timeout_s) const;

 private:
  void loop();
  void applyPending();  // sim side: reset, knobs, step safety
  void advanceFrame();  // sim side
  void publish(const FrameReport* report, double advance_ms);

  std::unique_ptr<SimulationModel> model_;
  ModelFactory factory_;
  double frame_dt_s_;
  bool threaded_;

  mutable std::mutex mutex_;
  mutable std::condition_variable cv_;
  std::vector<ViewerKnob> knobs_;
  std::vector<char> knob_dirty_;
  std::vector<double> knob_applied_;  // last value whose edit reached the scene (undo on a failed rebuild)
  std::vector<ToolEvent> tool_queue_;
  bool paused_ = false;
  int steps_requested_ = 0;
  bool reset_requested_ = false;
  bool layers_wanted_ = false, republish_ = false;
  double time_scale_ = 1.0;
  double step_safety_ = 1.0, applied_step_safety_ = 1.0;
  bool stop_ = false;
  SimSnapshot snapshot_;
  std::uint64_t version_ = 0;
  std::thread worker_;
};

}  // namespace inc::viewer
