// The memory estimate: above what the built models take, and a scene that will not fit refused before any build.
#include <gtest/gtest.h>

#include <string>

#include "host/app/memory_estimate.h"
#include "host/app/runner.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "model/input_error.h"
#include "tests/support/temp_dir.h"

using namespace inc;

namespace {

Scene boxScene(double size, double spacing, const std::string& models) {
  return parseScene(R"({"geometry": {"kind": "box", "center_m": [0, 0, 0], "size_m": [)" + std::to_string(size) + ", " +
                        std::to_string(size) + ", " + std::to_string(size) + R"(], "spacing_m": )" +
                        std::to_string(spacing) + R"(},
                        "models": {)" +
                        models + R"(},
                        "fixed": [{"min_m": [-1, -1, -1], "max_m": [1, 1, -0.01]}],
                        "solver": {"backend": "cpu"},
                        "output": {"particles_ply": false, "mesh_obj": false, "metrics_csv": false}})",
                    "<box>", ".");
}

std::size_t builtHostBytes(const Scene& s) {
  std::size_t b = 0;
  for (const auto& m : createSceneModels(compileScene(s), BackendKind::Cpu)) b += m->memory().host_bytes;
  return b;
}

// The key the check names, or "<fits>".
std::string refusedKey(const Scene& s, std::size_t host_bytes) {
  MemoryBudget budget;
  budget.host_bytes = host_bytes;
  budget.host_source = "test budget";
  try {
    checkSceneMemory(s, BackendKind::Cpu, budget);
  } catch (const InputError& e) {
    return e.key();
  }
  return "<fits>";
}

}  // namespace

TEST(MemoryEstimate, IsAboveWhatTheBuiltModelsTakeAndNotFarAbove) {
  for (const char* models : {R"("mls": true)", R"("pbd_metaballs": true)"})
    for (const char* precision : {"float32", "float64"}) {
      Scene s = boxScene(0.03, 0.0015, models);  // 8000 particles or spheres
      s.solver.precision = std::string(precision) == "float64" ? Precision::Float64 : Precision::Float32;
      const std::size_t built = builtHostBytes(s);
      const std::size_t estimate = estimateSceneMemory(s, BackendKind::Cpu).bytes.host_bytes;
      std::printf("[ memory ] %s %s: estimate %.1f MiB, built models %.1f MiB\n", models, precision,
                  estimate / 1048576.0, built / 1048576.0);
      EXPECT_GT(estimate, built) << models << " " << precision;
      EXPECT_LT(estimate, 4 * built) << models << " " << precision;
    }
}

// Issue 31: 3.9e7 particles (under the loader's 5e7 cap) passed validate, then failed after 28 s and 3.5 GB with a
// message naming neither the file nor a key. ~1.3 KB a particle: about 47 GiB.
TEST(MemoryEstimate, AHugeSceneIsRefusedNamingTheKeyThatSetsItsSize) {
  const Scene huge = boxScene(0.34, 0.001, R"("mls": true)");
  const SceneMemoryEstimate e = estimateSceneMemory(huge, BackendKind::Cpu);
  EXPECT_GT(e.bytes.host_bytes, std::size_t(40) << 30) << e.detail;
  EXPECT_EQ(refusedKey(huge, std::size_t(32) << 30), "geometry.spacing_m");
  EXPECT_EQ(refusedKey(huge, std::size_t(1) << 40), "<fits>");  // a 1 TiB host would hold it
  // A packed organ's size is its sphere count.
  Scene packed = boxScene(0.1, 0.005, R"("pbd_metaballs": true)");
  packed.pbd.target_spheres = 20000000;
  EXPECT_EQ(refusedKey(packed, std::size_t(16) << 30), "pbd.target_spheres");
  // The message says how much, of what, per model.
  MemoryBudget small;
  small.host_bytes = std::size_t(1) << 30;
  small.host_source = "test budget";
  try {
    checkSceneMemory(huge, BackendKind::Cpu, small);
    ADD_FAILURE();
  } catch (const InputError& err) {
    const std::string m = err.what();
    EXPECT_NE(m.find("<box>: geometry.spacing_m"), std::string::npos) << m;
    EXPECT_NE(m.find("GiB of host memory"), std::string::npos) << m;
    EXPECT_NE(m.find("mls: 3.93e+07 particles"), std::string::npos) << m;
  }
  // On the CUDA backend the device's memory is checked too.
  MemoryBudget gpu;
  gpu.host_bytes = std::size_t(1) << 40;
  gpu.device_bytes = std::size_t(8) << 30;
  EXPECT_THROW(checkSceneMemory(huge, BackendKind::Cuda, gpu), InputError);
}

TEST(MemoryEstimate, RunRefusesBeforeBuildingAnything) {
  const test::TempDir tmp("memory_run");
  RunOptions opt;
  opt.frames = 1;
  opt.out_dir = tmp.str();
  opt.quiet = true;
  opt.memory_budget = MemoryBudget{};
  opt.memory_budget->host_bytes = 1 << 20;  // 1 MiB: the 8000-particle block needs ~10 MiB
  bool built = false;
  try {
    runScene(boxScene(0.03, 0.0015, R"("mls": true)"), opt, [&](const CompiledScene& c, BackendKind b) {
      built = true;
      return createSceneModels(c, b);
    });
    ADD_FAILURE() << "the scene must be refused";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "geometry.spacing_m");
  }
  EXPECT_FALSE(built);
  EXPECT_GT(machineMemoryBudget(BackendChoice{}).host_bytes, 0u);
}
