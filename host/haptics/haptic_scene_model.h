// A scene model with its haptic loop beside it: the frame hooks around advance() and the hand's force arrow.
#pragma once

#include <memory>
#include <vector>

#include "host/haptics/scene_haptics.h"
#include "host/sim/simulation_model.h"

namespace inc {

// Wraps the model a haptics scene's tools touch (the runner's and the viewer's model) and its SceneHaptics:
// advance() hands the cut decisions to the model before the frame and publishes the data time and the counters
// haptic_hz, haptic_p99_ms, ... of each loop after it; renderLayers() adds the force on each hand as a Tool arrow at
// its device's tip. Everything else is the wrapped model's. The loops start here and stop when the model is
// destroyed.
class HapticSceneModel final : public SimulationModel {
 public:
  HapticSceneModel(std::unique_ptr<SimulationModel> model, const CompiledScene& scene,
                   SceneHapticsOptions options = {});
  ~HapticSceneModel() override;

  SceneHaptics& haptics() { return *haptics_; }
  SimulationModel& inner() { return *model_; }

  std::string name() const override { return model_->name(); }
  BackendKind backend() const override { return model_->backend(); }
  std::size_t particleCount() const override { return model_->particleCount(); }
  FrameReport advance(double frame_dt) override;
  void saveCheckpoint() override { model_->saveCheckpoint(); }
  void restoreCheckpoint() override { model_->restoreCheckpoint(); }
  void scaleTimeStep(double factor) override { model_->scaleTimeStep(factor); }
  void currentPositions(std::vector<Vec3d>& out) const override { model_->currentPositions(out); }
  bool currentSurface(TriangleMesh& out) const override { return model_->currentSurface(out); }
  MemoryReport memory() const override;
  ToolSupport toolSupport() const override { return model_->toolSupport(); }
  ToolResult applyTool(const ToolEvent& event) override { return model_->applyTool(event); }
  void cutWallTriangles(std::vector<std::uint8_t>& out) const override { model_->cutWallTriangles(out); }
  void renderLayers(RenderLayers& out) const override;

 private:
  std::unique_ptr<SimulationModel> model_;
  std::unique_ptr<SceneHaptics> haptics_;
};

// The runner's and the viewer's wrapping: `model` itself when the scene does not switch on models.haptics (a
// scene pays nothing for haptics it does not use), else a HapticSceneModel around it.
std::unique_ptr<SimulationModel> withSceneHaptics(std::unique_ptr<SimulationModel> model, const CompiledScene& scene,
                                                  SceneHapticsOptions options = {});
// The runner's: wraps the model the tool touches (the first that can be cut, else the first) when the scene
// switches on models.haptics, and returns it; nullptr (and nothing changed) otherwise.
HapticSceneModel* attachSceneHaptics(std::vector<std::unique_ptr<SimulationModel>>& models, const CompiledScene& scene,
                                     SceneHapticsOptions options = {});

}  // namespace inc
