// The viewer's simulation loop: commands in under a mutex, the model touched only by the stepping thread.
#include "viewer/sim_runner.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "host/input_error.h"

namespace inc::viewer {

namespace {
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
}  // namespace

SimRunner::SimRunner(std::unique_ptr<SimulationModel> model, ModelFactory factory, std::vector<ViewerKnob> knobs,
                     double frame_dt_s, bool threaded)
    : model_(std::move(model)), factory_(std::move(factory)), frame_dt_s_(frame_dt_s), threaded_(threaded),
      knobs_(std::move(knobs)) {
  if (!(frame_dt_s > 0.0) || !std::isfinite(frame_dt_s))
    throw InputError("viewer", "frame_dt", "must be a positive number of seconds");
  if (!model_ && factory_) model_ = factory_();
  if (!model_) throw InputError("viewer", "model", "no model and no factory to build one");
  for (auto& k : knobs_) {
    if (!(k.min_value <= k.max_value)) throw InputError("viewer", "knob " + k.label, "min exceeds max");
    if (k.logarithmic && !(k.min_value > 0.0)) throw InputError("viewer", "knob " + k.label, "logarithmic needs min > 0");
    k.value = std::clamp(k.value, k.min_value, k.max_value);
  }
  knob_dirty_.assign(knobs_.size(), 0);
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

void SimRunner::applyPending() {
  bool do_reset;
  std::vector<std::pair<std::size_t, double>> changes;
  double safety_ratio;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    do_reset = reset_requested_;
    reset_requested_ = false;
    for (std::size_t i = 0; i < knobs_.size(); ++i)
      if (knob_dirty_[i] || do_reset) {
        changes.emplace_back(i, knobs_[i].value);
        knob_dirty_[i] = 0;
      }
    safety_ratio = do_reset ? step_safety_ : step_safety_ / applied_step_safety_;
    applied_step_safety_ = step_safety_;
  }
  if (do_reset) {
    model_ = factory_();
    std::lock_guard<std::mutex> lock(mutex_);
    snapshot_.frame = 0;
    snapshot_.sim_time_s = 0.0;
    snapshot_.failed = false;
    snapshot_.failure.clear();
    snapshot_.report = FrameReport{};
  }
  for (const auto& [i, v] : changes)
    if (knobs_[i].apply) knobs_[i].apply(*model_, v);
  if (safety_ratio != 1.0) model_->scaleTimeStep(safety_ratio);
  if (do_reset) {
    model_->saveCheckpoint();
    publish(nullptr, 0.0);
  }
}

void SimRunner::advanceFrame() {
  double dt;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    dt = frame_dt_s_ * time_scale_;
  }
  const auto t0 = Clock::now();
  const FrameReport report = model_->advance(dt);
  const double ms = msSince(t0);
  if (!report.finite) {
    // Never show a lie: roll back to the last good state and stop until the user changes something.
    model_->restoreCheckpoint();
    std::lock_guard<std::mutex> lock(mutex_);
    paused_ = true;
    snapshot_.failed = true;
    snapshot_.failure = "non-finite state in stage '" + report.failure_stage + "' at particle " +
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
  std::lock_guard<std::mutex> lock(mutex_);
  snapshot_.positions.swap(positions);
  snapshot_.surface = std::move(surface);
  snapshot_.has_surface = has_surface;
  if (report) snapshot_.report = *report;
  snapshot_.advance_ms = advance_ms;
  snapshot_.name = model_->name();
  snapshot_.backend = model_->backend();
  snapshot_.particles = model_->particleCount();
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
        return stop_ || !paused_ || steps_requested_ > 0 || reset_requested_ ||
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
