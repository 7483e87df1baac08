// Scene keys of the haptic cutting force model: material.cutting.{press_threshold_n, static_friction_n, ...}.
#include "host/scene/cutting_scene.h"

#include "host/compiled/material_checks.h"
#include "host/scene/scene_fields.h"
#include "host/scene/scene_keys.h"

namespace inc {

CutThresholds<double> readCutThresholds(const scene_json::ObjectReader& r) {
  r.allowOnly(sceneKeysUnder("material.cutting"));
  CutThresholds<double> th;
  // The table's reads refuse NaN / infinity and non-numbers with the key path; ranges are checked below
  // in one place (validateCutThresholds) so the haptic code and the scene agree on them.
  readSceneKeys(r, "material.cutting", th);
  validateCutThresholds(th, r.file(), r.path());
  return th;
}

}  // namespace inc
