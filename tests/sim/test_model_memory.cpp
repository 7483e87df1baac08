// A scene pays only for the models it switches on: a PBD-only scene builds and allocates nothing of MLS.
#include <gtest/gtest.h>

#include "host/app/runner.h"
#include "host/scene/embedded_scenes.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "tests/support/temp_dir.h"

using namespace inc;

namespace {

Scene beam(bool mls, bool pbd) {
  Scene s = parseScene(findEmbeddedScene("beam")->json, "<embedded:beam>", ".");
  s.geometry.size = {0.04, 0.016, 0.016};
  s.geometry.center = {0.02, 0, 0};
  s.fixed = {FixedRegion{{-0.001, -0.009, -0.009}, {0.0041, 0.009, 0.009}}};
  s.models.mls = mls;
  s.models.pbd_metaballs = pbd;
  s.output.particles_ply = s.output.mesh_obj = s.output.vtk = false;
  return s;
}

std::size_t hostBytes(const Scene& s) {
  std::size_t b = 0;
  for (const auto& m : createSceneModels(compileScene(s), BackendKind::Cpu)) b += m->memory().host_bytes;
  return b;
}

}  // namespace

TEST(ModelMemory, PbdOnlySceneBuildsNoMlsModelAndItsMemoryIsThePbdModelsAlone) {
  const auto pbd_only = createSceneModels(compileScene(beam(false, true)), BackendKind::Cpu);
  ASSERT_EQ(pbd_only.size(), 1u);
  EXPECT_EQ(pbd_only[0]->name(), "pbd_metaballs");
  const std::size_t pbd = hostBytes(beam(false, true)), mls = hostBytes(beam(true, false)),
                    both = hostBytes(beam(true, true));
  EXPECT_GT(pbd, 0u);
  EXPECT_GT(mls, 0u);
  // Memory adds up model by model (exact: each model reports its own arrays, nothing is shared or hidden).
  EXPECT_EQ(both, pbd + mls);

  // The run summary (what the user sees) shows the same: models "pbd_metaballs" only, PBD memory only.
  RunOptions o;
  o.frames = 2;
  o.quiet = true;
  o.backend = BackendKind::Cpu;
  const test::TempDir out("model_memory");
  o.out_dir = out.str();
  const RunSummary s = runScene(beam(false, true), o);
  EXPECT_FALSE(s.failed) << s.failure;
  EXPECT_EQ(s.model_names, "pbd_metaballs");
  EXPECT_EQ(s.memory.host_bytes, pbd);
  EXPECT_EQ(s.memory.device_bytes, 0u);  // CPU backend: nothing on a device
  EXPECT_EQ(s.line().find("mls"), std::string::npos);
  // After a run (checkpoints and per-frame buffers exist) the figures still add up model by model.
  const RunSummary sm = runScene(beam(true, false), o);
  const RunSummary sb = runScene(beam(true, true), o);
  EXPECT_EQ(sm.model_names, "mls");
  EXPECT_EQ(sb.model_names, "mls+pbd_metaballs");
  EXPECT_EQ(sb.memory.host_bytes, sm.memory.host_bytes + s.memory.host_bytes);
  EXPECT_GT(sb.memory.host_bytes, s.memory.host_bytes);
}
