// HapticSceneModel: frame hooks of the scene's haptic loop around the wrapped model, and the force arrow.
#include "host/haptics/haptic_scene_model.h"

#include "model/input_error.h"

namespace inc {

HapticSceneModel::HapticSceneModel(std::unique_ptr<SimulationModel> model, const CompiledScene& scene,
                                   SceneHapticsOptions options)
    : model_(std::move(model)) {
  if (!model_) throw InputError(scene.file, "models.haptics", "no model for the haptic tool to touch");
  haptics_ = std::make_unique<SceneHaptics>(scene, *model_, std::move(options));
  haptics_->start();
}

HapticSceneModel::~HapticSceneModel() { haptics_->stop(); }

FrameReport HapticSceneModel::advance(double frame_dt) {
  haptics_->beforeFrame(*model_);
  FrameReport r = model_->advance(frame_dt);
  haptics_->afterFrame(r);
  return r;
}

MemoryReport HapticSceneModel::memory() const {
  MemoryReport m = model_->memory();
  for (std::size_t k = 0; k < haptics_->handCount(); ++k)
    m.host_bytes += haptics_->loop(k).records().capacity() * sizeof(TickRecord);
  return m;
}

void HapticSceneModel::renderLayers(RenderLayers& out) const {
  model_->renderLayers(out);
  for (std::size_t k = 0; k < haptics_->handCount(); ++k) {
    const HapticStatus& s = haptics_->newest(k);
    if (s.tick > 0) out.forces.push_back(ForceArrow{s.sample.position_m, s.force_n, ForceArrowKind::Tool});
  }
}

std::unique_ptr<SimulationModel> withSceneHaptics(std::unique_ptr<SimulationModel> model, const CompiledScene& scene,
                                                  SceneHapticsOptions options) {
  if (!scene.models.haptics || !model) return model;
  return std::make_unique<HapticSceneModel>(std::move(model), scene, std::move(options));
}

HapticSceneModel* attachSceneHaptics(std::vector<std::unique_ptr<SimulationModel>>& models, const CompiledScene& scene,
                                     SceneHapticsOptions options) {
  if (!scene.models.haptics || models.empty()) return nullptr;
  std::size_t k = 0;
  for (std::size_t i = 0; i < models.size(); ++i)
    if (models[i]->toolSupport().cut) {
      k = i;
      break;
    }
  auto wrapped = std::make_unique<HapticSceneModel>(std::move(models[k]), scene, std::move(options));
  HapticSceneModel* out = wrapped.get();
  models[k] = std::move(wrapped);
  return out;
}

}  // namespace inc
