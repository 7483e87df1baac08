// The viewer's simulation loop: commands in under a mutex, the model touched only by the stepping thread.
#include "viewer/sim_runner.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "model/input_error.h"

namespace inc::viewer {

namespace {
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
}  // namespace

SimRunner::SimRunner(std::unique_ptr<SimulationModel> model, ModelFactory factory, std::vector<ViewerKnob> knobs,
                     double frame_dt_s, bool threaded)
    : model_(std::move(model)),
      factory_(std::move(factory)),
      frame_dt_s_(frame_dt_s),
      threaded_(threaded),
      knobs_(std::move(knobs)) {
  if (!(frame_dt_s > 0.0) || !std::isfinite(frame_dt_s))
    throw InputError("viewer", "frame_dt", "must be a positive number of seconds");
  if (!model_ && factory_) model_ = factory_();
  if (!model_) throw InputError("viewer", "model", "no model and no factory to build one");
  for (auto& k : knobs_) {
    if (!k.choices.empty()) {
      k.min_value = 0.0;
      k.max_value = double(k.choices.size() - 1);
      k.integer = true;
      k.logarithmic = false;
    }
    if (!(k.min_value <= k.max_value)) throw InputError("viewer", "knob " + k.label, "min exceeds max");
    if (k.logarithmic && !(k.min_value > 0.0))
      throw InputError("viewer", "knob " + k.label, "logarithmic needs min > 0");
    k.value = std::clamp(k.value, k.min_value, k.max_value);
  }
  knob_dirty_.assign(knobs_.size(), 0);
  for (const auto& k : knobs_) {
    knob_applied_.push_back(k.value);
    if (k.frame_dt && k.value > 0.0) frame_dt_s_ = k.value;
  }
  model_->saveCheckpoint();
  publish(nullptr, 0.0);
  if (threaded_) worker_ = std::thread([this] { loop(); });
}

SimRunner::~SimRunner() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void SimRunner::setPaused(bool paused) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    paused_ = paused;
  }
  cv_.notify_all();
}

bool SimRunner::paused() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return paused_;
}

void SimRunner::stepOnce() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++steps_requested_;
  }
  cv_.notify_all();
}

void SimRunner::reset() {
  if (!factory_) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    reset_requested_ = true;
  }
  cv_.notify_all();
}

void SimRunner::setTimeScale(double scale) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (scale > 0.0 && std::isfinite(scale)) time_scale_ = std::min(scale, 1.0);
}

double SimRunner::timeScale() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return time_scale_;
}

void SimRunner::setStepSafety(double factor) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (factor > 0.0 && std::isfinite(factor)) step_safety_ = factor;
}

double SimRunner::stepSafety() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return step_safety_;
}

void SimRunner::setKnob(std::size_t index, double value) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (index >= knobs_.size() || !std::isfinite(value)) return;
  ViewerKnob& k = knobs_[index];
  k.value = std::clamp(k.integer ? std::round(value) : value, k.min_value, k.max_value);
  knob_dirty_[index] = 1;
}

std::vector<ViewerKnob> SimRunner::knobs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return knobs_;
}

double SimRunner::frameDt() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return frame_dt_s_;
}

void SimRunner::queueTool(const ToolEvent& event) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    tool_queue_.push_back(event);
  }
  cv_.notify_all();
}

void SimRunner::setLayersWanted(bool wanted) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (wanted && !layers_wanted_) republish_ = true;
    layers_wanted_ = wanted;
  }
  cv_.notify_all();
}

void SimRunner::applyPending() {
  bool do_reset, rebuild = false, republish;
  std::vector<std::size_t> changed;
  std::vector<double> values;
  std::vector<ToolEvent> tools;
  double safety, safety_ratio;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    do_reset = reset_requested_ && bool(factory_);
    reset_requested_ = false;
    republish = republish_;
    republish_ = false;
    for (std::size_t i = 0; i < knobs_.size(); ++i) {
      values.push_back(knobs_[i].value);
      if (!knob_dirty_[i]) continue;
      knob_dirty_[i] = 0;
      changed.push_back(i);
      if (knobs_[i].frame_dt) {
        if (knobs_[i].value > 0.0) frame_dt_s_ = knobs_[i].value;
      } else if (knobs_[i].edit && knobs_[i].value != knob_applied_[i]) {
        rebuild = bool(factory_);
      }
    }
    tools.swap(tool_queue_);
    safety = step_safety_;
    safety_ratio = step_safety_ / applied_step_safety_;
    applied_step_safety_ = step_safety_;
  }
  // The time step also goes into the scene (later rebuilds check their substeps against it), with no rebuild.
  for (std::size_t i : changed)
    if (knobs_[i].frame_dt && knobs_[i].edit) {
      knobs_[i].edit(values[i]);
      knob_applied_[i] = values[i];
    }
  bool fresh = false;
  if (do_reset || rebuild) {
    // Scene edits first, then one model built from the edited scene; a failed build undoes the edits.
    std::vector<std::pair<std::size_t, double>> undo;
    for (std::size_t i = 0; i < knobs_.size(); ++i)
      if (knobs_[i].edit && !knobs_[i].frame_dt && values[i] != knob_applied_[i]) {
        knobs_[i].edit(values[i]);
        undo.emplace_back(i, knob_applied_[i]);
      }
    std::string error;
    try {
      std::unique_ptr<SimulationModel> m = factory_();
      if (!m) throw InputError("viewer", "model", "the factory built no model");
      model_ = std::move(m);
      fresh = true;
      for (const auto& [i, old] : undo) knob_applied_[i] = values[i];
    } catch (const std::exception& e) {
      error = e.what();
      for (const auto& [i, old] : undo) {
        knobs_[i].edit(old);
        values[i] = old;
      }
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (fresh) {
      snapshot_.frame = 0;
      snapshot_.sim_time_s = 0.0;
      snapshot_.failed = false;
      snapshot_.failure.clear();
      snapshot_.report = FrameReport{};
      snapshot_.message.clear();
      ++snapshot_.rebuilds;
    } else {
      snapshot_.message = "model not rebuilt (kept the previous one): " + error;
      for (const auto& [i, old] : undo) knobs_[i].value = old;
    }
  }
  // Live knobs: every one on a fresh model, the changed ones otherwise.
  for (std::size_t i = 0; i < knobs_.size(); ++i) {
    const bool touched = fresh || std::find(changed.begin(), changed.end(), i) != changed.end();
    if (touched && knobs_[i].apply) knobs_[i].apply(*model_, values[i]);
  }
  if (fresh) safety_ratio = safety;
  if (safety_ratio != 1.0) model_->scaleTimeStep(safety_ratio);
  if (fresh) model_->saveCheckpoint();
  // The interactive tool's events, in order, before the frame is advanced.
  for (const ToolEvent& e : tools) {
    try {
      const ToolResult r = model_->applyTool(e);
      std::lock_guard<std::mutex> lock(mutex_);
      snapshot_.last_tool = r;
      if (!r.supported) snapshot_.message = r.message;
    } catch (const std::exception& ex) {
      std::lock_guard<std::mutex> lock(mutex_);
      snapshot_.message = std::string("tool: ") + ex.what();
    }
  }
  bool show_now = fresh || republish;
  if (!tools.empty()) {
    std::lock_guard<std::mutex> lock(mutex_);
    show_now = show_now || (paused_ && steps_requested_ == 0);  // a cut while paused shows at once
  }
  if (show_now) publish(nullptr, 0.0);
}

void SimRunner::advanceFrame() {
  double dt;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    dt = frame_dt_s_ * time_scale_;
  }
  const auto t0 = Clock::now();
  FrameReport report;
  try {
    report = model_->advance(dt);
  } catch (const std::exception& e) {
    // A model that refuses the frame (e.g. a fixed substep count unstable for a longer time step): keep the
    // last good state, pause and say why instead of taking the UI down.
    model_->restoreCheckpoint();
    std::lock_guard<std::mutex> lock(mutex_);
    paused_ = true;
    snapshot_.message = std::string("frame refused, paused: ") + e.what();
    ++version_;
    cv_.notify_all();
    return;
  }
  const double ms = msSince(t0);
  if (!report.finite) {
    // Never show a lie: roll back to the last good state and stop until the user changes something.
    model_->restoreCheckpoint();
    std::lock_guard<std::mutex> lock(mutex_);
    paused_ = true;
    snapshot_.failed = true;
    // A frame refused for the frame budget (model/frame_budget.h) says what to change; it never ran.
    snapshot_.failure = report.refused ? "frame refused, paused: " + report.failure_reason
                                       : "non-finite state in stage '" + report.failure_stage + "' at particle " +
                                             std::to_string(report.failure_particle) + "; rolled back and paused";
    snapshot_.report = report;
    ++version_;
    cv_.notify_all();
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    snapshot_.sim_time_s += dt;
    ++snapshot_.frame;
  }
  publish(&report, ms);
}

void SimRunner::publish(const FrameReport* report, double advance_ms) {
  std::vector<Vec3d> positions;
  model_->currentPositions(positions);
  TriangleMesh surface;
  const bool has_surface = model_->currentSurface(surface);
  bool wanted;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    wanted = layers_wanted_;
  }
  RenderLayers layers;
  if (wanted) model_->renderLayers(layers);
  std::lock_guard<std::mutex> lock(mutex_);
  snapshot_.layers = std::move(layers);
  snapshot_.positions.swap(positions);
  snapshot_.surface = std::move(surface);
  snapshot_.has_surface = has_surface;
  if (report) snapshot_.report = *report;
  snapshot_.advance_ms = advance_ms;
  snapshot_.name = model_->name();
  snapshot_.backend = model_->backend();
  snapshot_.particles = model_->particleCount();
  snapshot_.tool_support = model_->toolSupport();
  model_->cutWallTriangles(snapshot_.cut_walls);
  ++version_;
  cv_.notify_all();
}

void SimRunner::pump() {
  if (threaded_) return;
  applyPending();
  bool go;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    go = !paused_ || steps_requested_ > 0;
    if (steps_requested_ > 0) --steps_requested_;
  }
  if (go) advanceFrame();
}

void SimRunner::loop() {
  auto next = Clock::now();
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [&] {
        return stop_ || !paused_ || steps_requested_ > 0 || reset_requested_ || republish_ || !tool_queue_.empty() ||
               std::find(knob_dirty_.begin(), knob_dirty_.end(), 1) != knob_dirty_.end();
      });
      if (stop_) return;
    }
    applyPending();
    bool go;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      go = !paused_ || steps_requested_ > 0;
      if (steps_requested_ > 0) --steps_requested_;
    }
    if (!go) continue;
    advanceFrame();
    // Real-time pacing: one frame per frame_dt of wall time; a slow step simply runs late (no catch-up burst).
    next += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(frame_dt_s_));
    const auto now = Clock::now();
    if (next < now) next = now;
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_until(lock, next, [&] { return stop_ || reset_requested_; });
  }
}

bool SimRunner::latest(SimSnapshot& out, std::uint64_t& version) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (version == version_) return false;
  out = snapshot_;
  version = version_;
  return true;
}

bool SimRunner::waitForFrame(std::uint64_t frame, double timeout_s) const {
  std::unique_lock<std::mutex> lock(mutex_);
  return cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                      [&] { return snapshot_.frame >= frame || snapshot_.failed; });
}

}  // namespace inc::viewer
