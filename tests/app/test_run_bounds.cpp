// Every run ends: the frame budget refuses a frame that needs too many substeps, and the guard's retries are bounded.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "host/app/runner.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "host/sim/dissection_simulation.h"
#include "model/frame_budget.h"
#include "model/input_error.h"
#include "tests/support/cut_block_scene.h"
#include "tests/support/temp_dir.h"

using namespace inc;

namespace {

// A test double whose every frame fails the guard on its first attempt (an energy blow-up) and passes on the retry;
// each halving of its step doubles its substeps, as a real model's cost. Before the retries were bounded, a run of
// it went on to the last frame, at twice the cost after every frame.
class FailsEveryFirstAttempt : public SimulationModel {
 public:
  explicit FailsEveryFirstAttempt(int& calls) : calls_(calls) {}
  std::string name() const override { return "flaky"; }
  BackendKind backend() const override { return BackendKind::Cpu; }
  std::size_t particleCount() const override { return 1; }
  FrameReport advance(double frame_dt) override {
    ++calls_;
    FrameReport r;
    r.substeps = int(10.0 / scale_);
    r.dt = frame_dt / r.substeps;
    r.kinetic_energy = retried_ ? 1e-6 : 1e9;  // far above energy_bound x the scene's floor
    retried_ = !retried_;
    return r;
  }
  void saveCheckpoint() override {}
  void restoreCheckpoint() override {}
  void scaleTimeStep(double f) override { scale_ *= f; }
  void currentPositions(std::vector<Vec3d>& out) const override { out = {Vec3d{0, 0, 0}, Vec3d{0.01, 0.01, 0.01}}; }
  MemoryReport memory() const override { return {}; }

  int& calls_;  // the test's: the model is gone when runScene returns
  bool retried_ = false;
  double scale_ = 1.0;
};

// A model whose frames the frame budget refuses (what MLS, PBD and the cut's nodal points report).
class AlwaysRefused : public FailsEveryFirstAttempt {
 public:
  using FailsEveryFirstAttempt::FailsEveryFirstAttempt;
  FrameReport advance(double frame_dt) override {
    ++calls_;
    FrameReport r;
    r.dt = frame_dt;
    refuseFrame(r, substepLimitReason("MLS substeps", 1e6, 20000, "automatic", kMlsSubstepKeys));
    return r;
  }
};

Scene testScene() {
  Scene s;
  s.name = "bounds";
  s.file = "<test>";
  s.solver.backend = BackendKind::Cpu;
  s.solver.frame_dt = 0.01;
  s.output.vtk = s.output.mesh_obj = s.output.particles_ply = false;
  s.output.metrics_csv = false;
  return s;
}

template <class M>
RunSummary runWith(const Scene& scene, long frames, const std::string& dir, int& calls) {
  RunOptions opt;
  if (frames > 0) opt.frames = frames;  // 0: the scene's duration
  opt.out_dir = dir;
  opt.quiet = true;
  return runScene(scene, opt, [&](const CompiledScene&, BackendKind) {
    std::vector<std::unique_ptr<SimulationModel>> m;
    m.push_back(std::make_unique<M>(calls));
    return m;
  });
}

// A small MLS block (4 x 4 x 4 particles, 1 cm apart) of Young's modulus `E`, the rest at the defaults.
Scene mlsBlock(double E) {
  Scene s = parseScene(R"({"geometry": {"kind": "box", "center_m": [0, 0, 0], "size_m": [0.04, 0.04, 0.04],
                           "spacing_m": 0.01},
                           "material": {"youngs_modulus_pa": 1000},
                           "models": {"mls": true},
                           "fixed": [{"min_m": [-1, -1, -1], "max_m": [1, 1, -0.012]}],
                           "solver": {"backend": "cpu"},
                           "output": {"particles_ply": false, "mesh_obj": false, "metrics_csv": false}})",
                       "<block>", ".");
  s.material.youngs_modulus_pa = E;
  return s;
}

}  // namespace

TEST(RunBounds, GuardRetriesAreBoundedAndTheRunEndsWithTheReason) {
  const test::TempDir tmp("bounds_retries");
  int calls = 0;
  const RunSummary s = runWith<FailsEveryFirstAttempt>(testScene(), 40, tmp.str(), calls);
  EXPECT_TRUE(s.failed) << "a model that fails every frame must not run on to the end at ever smaller steps";
  EXPECT_EQ(s.retries, kMaxGuardRetries);
  EXPECT_EQ(s.frames_done, kMaxGuardRetries);  // each retried frame passed; the next failure ends the run
  EXPECT_EQ(calls, 2 * kMaxGuardRetries + 1);
  EXPECT_NE(s.failure.find("energy blow-up"), std::string::npos) << s.failure;
  EXPECT_NE(s.failure.find("halved the step 3 times"), std::string::npos) << s.failure;
  EXPECT_TRUE(std::filesystem::exists(tmp.path() / "summary.txt"));
}

TEST(RunBounds, ARefusedFrameIsNotRetriedAndNamesTheKeys) {
  const test::TempDir tmp("bounds_refused");
  int calls = 0;
  const RunSummary s = runWith<AlwaysRefused>(testScene(), 10, tmp.str(), calls);
  EXPECT_TRUE(s.failed);
  EXPECT_EQ(s.retries, 0);  // half the step would need twice the substeps
  EXPECT_EQ(s.frames_done, 0);
  EXPECT_EQ(calls, 1);
  for (const char* key : {"substep_limit", "geometry.spacing_m", "material.youngs_modulus_pa", "solver.frame_dt_s",
                          "solver.max_substeps"})
    EXPECT_NE(s.failure.find(key), std::string::npos) << key << " in: " << s.failure;
}

TEST(RunBounds, FrameSubstepLimitFollowsTheFrameBudget) {
  EXPECT_EQ(frameSubstepLimit(2048, 0), 4882);     // the beam scene's 2048 points (it takes <= 267)
  EXPECT_EQ(frameSubstepLimit(64, 0), 20000);      // small models: the ceiling
  EXPECT_EQ(frameSubstepLimit(1000000, 0), 1000);  // large models: the floor
  EXPECT_EQ(frameSubstepLimit(64, 77), 77);        // solver.max_substeps replaces the rule
}

// E = 1e11 Pa on a 1 cm lattice needs ~9e4 substeps per 1/60 s frame (stable step ~3.6e-7 s, safety 0.5), above the
// limit of 20000 for 64 points. Before the frame budget the run took them all (minutes per frame on a larger model).
TEST(RunBounds, AnMlsBodyNeedingMoreSubstepsThanTheLimitIsRefusedAtOnce) {
  const test::TempDir tmp("bounds_mls");
  RunOptions opt;
  opt.frames = 2;
  opt.out_dir = tmp.str();
  opt.quiet = true;
  const RunSummary s = runScene(mlsBlock(1e11), opt);
  EXPECT_TRUE(s.failed);
  EXPECT_EQ(s.frames_done, 0);
  EXPECT_EQ(s.total_substeps, 0);
  EXPECT_EQ(s.retries, 0);
  for (const char* key : {"stage 'substep_limit'", "MLS substeps", "limit of 20000", "geometry.spacing_m",
                          "material.youngs_modulus_pa", "solver.max_substeps"})
    EXPECT_NE(s.failure.find(key), std::string::npos) << key << " in: " << s.failure;
  EXPECT_TRUE(std::filesystem::exists(tmp.path() / "summary.txt"));

  // The same block at a soft E runs; solver.max_substeps below its need refuses it, naming the key.
  const RunSummary soft = runScene(mlsBlock(1e4), opt);
  EXPECT_FALSE(soft.failed) << soft.failure;
  Scene capped = mlsBlock(1e4);
  capped.solver.max_substeps = 1;
  const RunSummary c = runScene(capped, opt);
  EXPECT_TRUE(c.failed);
  EXPECT_NE(c.failure.find("solver.max_substeps = 1"), std::string::npos) << c.failure;
  // A fixed solver.substeps above the limit is a contradiction in the scene: refused at load.
  Scene fixed = mlsBlock(1e4);
  fixed.solver.substeps = 50;
  fixed.solver.max_substeps = 10;
  try {
    runScene(fixed, opt);
    ADD_FAILURE() << "a fixed count above the limit must be refused";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "solver.substeps");
  }
}

TEST(RunBounds, PbdSubstepsAboveTheLimitAreRefused) {
  const test::TempDir tmp("bounds_pbd");
  Scene s = mlsBlock(1e4);
  s.models.mls = false;
  s.models.pbd_metaballs = true;
  s.solver.max_substeps = 2;  // the organ takes 4 substeps per frame
  RunOptions opt;
  opt.frames = 2;
  opt.out_dir = tmp.str();
  opt.quiet = true;
  const RunSummary r = runScene(s, opt);
  EXPECT_TRUE(r.failed);
  EXPECT_EQ(r.retries, 0);
  EXPECT_NE(r.failure.find("PBD substeps"), std::string::npos) << r.failure;
  EXPECT_NE(r.failure.find("solver.substeps"), std::string::npos) << r.failure;
}

// The scene's own duration is bounded like --steps and --seconds: 1e9 s of 1/100 s frames would never end.
TEST(RunBounds, ASceneDurationOfMoreFramesThanTheRunnerTakesIsRefused) {
  const test::TempDir tmp("bounds_duration");
  Scene s = testScene();
  s.duration = 1.0e9;
  int calls = 0;
  try {
    runWith<FailsEveryFirstAttempt>(s, 0, tmp.str(), calls);
    ADD_FAILURE() << "the run must be refused";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "duration_s");
  }
  EXPECT_EQ(calls, 0);
}

// Issue 31's cut: nodal points whose stable step asked for 229,075 substeps in one frame (146 s), then ~40 s a frame
// after the guard's retry. Here a block of E = 5e10 Pa: its nodal points (1 cm spheres, 3 cells across) need ~1.3e5
// substeps per frame, above the limit of 20000 for so few points: the first frame of the stroke is refused before
// it steps, naming the points and the keys. (The old clamp at 1e7 substeps per exchange let it run.)
TEST(RunBounds, ACutWhoseNodalPointsNeedTooManySubstepsIsRefused) {
  Scene s = cuttest::dissectionBlock("<test:stiff_cut>");
  s.material.youngs_modulus_pa = 5e10;
  s.cutting.samples_per_diameter = 3;
  s.cutting.exchanges_per_frame = 2;
  s.tools = {cuttest::straightScalpel(0.0, 0.3)};
  auto sim = makeDissectionSimulation(compileScene(s), BackendKind::Cpu, Precision::Float32);
  FrameReport rep;
  int f = 0;
  for (; f < 8; ++f) {
    rep = sim->advance(1.0 / 60.0);
    if (!rep.finite) break;
    EXPECT_EQ(rep.counters.at("nodal_points"), 0.0)
        << "frame " << f << " stepped nodal points: " << rep.counters.at("mls_substeps") << " substeps";
  }
  ASSERT_FALSE(rep.finite) << "the stroke's nodal points must be refused";
  EXPECT_TRUE(rep.refused);
  EXPECT_EQ(rep.failure_stage, "substep_limit");
  for (const char* key : {"nodal points", "cutting.samples_per_diameter", "material.youngs_modulus_pa",
                          "solver.max_substeps", "cutting.exchanges_per_frame = 2"})
    EXPECT_NE(rep.failure_reason.find(key), std::string::npos) << key << " in: " << rep.failure_reason;
}
