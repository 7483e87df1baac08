// Tests for the headless runner: frame count, metrics rows, the guard's rollback/retry and last-good output.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "host/app/runner.h"
#include "host/sim/numerical_guard.h"
#include "model/input_error.h"
#include "tests/support/temp_dir.h"

using namespace inc;
namespace fs = std::filesystem;

namespace {

// A test double: N particles on harmonic springs to their rest positions (exact energy known), which can
// be told to produce NaN or an energy explosion when its step is larger than a threshold.
class OscillatorModel : public SimulationModel {
 public:
  explicit OscillatorModel(int n, double unstable_above_dt = 1e9, long nan_at_frame = -1)
      : unstable_dt_(unstable_above_dt), nan_frame_(nan_at_frame) {
    for (int i = 0; i < n; ++i) {
      rest_.push_back({0.01 * i, 0, 0});
      x_.push_back(rest_.back() + Vec3d{0, 0, 0.001});
      v_.push_back({0, 0, 0});
    }
  }
  std::string name() const override { return "oscillator"; }
  BackendKind backend() const override { return BackendKind::Cpu; }
  std::size_t particleCount() const override { return x_.size(); }
  FrameReport advance(double frame_dt) override {
    ++frame_;
    FrameReport r;
    const double h = 0.001 * scale_;
    r.substeps = int(std::ceil(frame_dt / h));
    r.dt = frame_dt / r.substeps;
    const double k = 100.0;
    for (int s = 0; s < r.substeps; ++s)
      for (std::size_t i = 0; i < x_.size(); ++i) {
        v_[i] -= k * (x_[i] - rest_[i]) * r.dt;  // symplectic Euler, unit mass
        x_[i] += v_[i] * r.dt;
      }
    if (r.dt > unstable_dt_) {  // pretend the scheme is unstable at this step: energy explodes
      for (auto& v : v_) v = v * 1e6;
    }
    if (frame_ == nan_frame_) x_[3].y = std::numeric_limits<double>::quiet_NaN();
    for (std::size_t i = 0; i < x_.size(); ++i) {
      r.kinetic_energy += 0.5 * norm2(v_[i]);
      r.elastic_energy += 0.5 * k * norm2(x_[i] - rest_[i]);
      if (!isFinite(x_[i]) && r.finite) {
        r.finite = false;
        r.failure_stage = "integrate";
        r.failure_particle = std::int64_t(i);
      }
      r.max_displacement = std::max(r.max_displacement, norm(x_[i] - rest_[i]));
    }
    r.stages = {{"integrate", 0.01}};
    return r;
  }
  void saveCheckpoint() override { cx_ = x_, cv_ = v_; }
  void restoreCheckpoint() override { x_ = cx_, v_ = cv_; }
  void scaleTimeStep(double f) override { scale_ *= f; }
  void currentPositions(std::vector<Vec3d>& out) const override { out = x_; }
  MemoryReport memory() const override { return {0, x_.size() * sizeof(Vec3d) * 4}; }

  double unstable_dt_;
  long nan_frame_;
  long frame_ = 0;
  double scale_ = 1.0;
  std::vector<Vec3d> rest_, x_, v_, cx_, cv_;
};

Scene oscillatorScene() {
  Scene s;
  s.name = "oscillator";
  s.file = "<test>";
  s.solver.backend = BackendKind::Cpu;
  s.solver.frame_dt = 0.01;
  s.material.density_kg_m3 = 1e7;  // makes the guard's energy scale (rho V g L) about 1e-3 J for this cloud
  s.output.vtk = false;
  s.output.mesh_obj = false;
  return s;
}

int countLines(const fs::path& p) {
  std::ifstream in(p);
  int n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

}  // namespace

TEST(Runner, RunsTheRequestedFramesAndWritesOutputs) {
  const test::TempDir tmp("runner_ok");
  const fs::path& dir = tmp.path();
  RunOptions opt;
  opt.frames = 25;
  opt.out_dir = dir.string();
  opt.quiet = true;
  auto factory = [](const CompiledScene&, BackendKind) {
    std::vector<std::unique_ptr<SimulationModel>> m;
    m.push_back(std::make_unique<OscillatorModel>(8));
    return m;
  };
  RunSummary s = runScene(oscillatorScene(), opt, factory);
  EXPECT_FALSE(s.failed) << s.failure;
  EXPECT_EQ(s.frames_done, 25);
  EXPECT_NEAR(s.simulated_s, 0.25, 1e-12);
  EXPECT_EQ(countLines(dir / "metrics.csv"), 26);  // header + one row per frame
  EXPECT_TRUE(fs::exists(dir / "final_oscillator_particles.ply"));
  EXPECT_TRUE(fs::exists(dir / "summary.txt"));
  // The oscillator conserves energy to first order in dt: 10 substeps per frame keep it within 5%.
  EXPECT_NEAR(s.final_total_energy, 8 * 0.5 * 100.0 * 1e-6, 0.05 * 8 * 0.5 * 100.0 * 1e-6);
}

TEST(Runner, SecondsSelectTheFrameCount) {
  RunOptions opt;
  opt.seconds = 0.05;
  const test::TempDir tmp("runner_seconds");
  opt.out_dir = tmp.str();
  opt.quiet = true;
  auto factory = [](const CompiledScene&, BackendKind) {
    std::vector<std::unique_ptr<SimulationModel>> m;
    m.push_back(std::make_unique<OscillatorModel>(4));
    return m;
  };
  EXPECT_EQ(runScene(oscillatorScene(), opt, factory).frames_done, 5);
}

TEST(Runner, GuardRetriesWithHalfTheStepAndRecovers) {
  RunOptions opt;
  opt.frames = 10;
  const test::TempDir tmp("runner_retry");
  opt.out_dir = tmp.str();
  opt.quiet = true;
  auto factory = [](const CompiledScene&, BackendKind) {
    std::vector<std::unique_ptr<SimulationModel>> m;
    // Unstable at dt = 1e-3 (the model's default), stable at 5e-4 after one halving.
    m.push_back(std::make_unique<OscillatorModel>(6, 0.75e-3));
    return m;
  };
  RunSummary s = runScene(oscillatorScene(), opt, factory);
  EXPECT_FALSE(s.failed) << s.failure;
  EXPECT_EQ(s.retries, 1);
  EXPECT_EQ(s.frames_done, 10);
}

TEST(Runner, NaNStopsWithStageParticleAndKeepsLastGoodState) {
  const test::TempDir tmp("runner_nan");
  const fs::path& dir = tmp.path();
  RunOptions opt;
  opt.frames = 20;
  opt.out_dir = dir.string();
  opt.quiet = true;
  opt.retry_once = false;
  auto factory = [](const CompiledScene&, BackendKind) {
    std::vector<std::unique_ptr<SimulationModel>> m;
    m.push_back(std::make_unique<OscillatorModel>(6, 1e9, 7));
    return m;
  };
  RunSummary s = runScene(oscillatorScene(), opt, factory);
  EXPECT_TRUE(s.failed);
  EXPECT_EQ(s.frames_done, 6);
  EXPECT_NE(s.failure.find("frame 7"), std::string::npos) << s.failure;
  EXPECT_NE(s.failure.find("integrate"), std::string::npos) << s.failure;
  EXPECT_NE(s.failure.find("particle 3"), std::string::npos) << s.failure;
  ASSERT_TRUE(fs::exists(dir / "last_good_oscillator_particles.ply"));
  std::ifstream in(dir / "last_good_oscillator_particles.ply");
  std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(all.find("nan"), std::string::npos) << "the last good state must not contain the NaN";
}

TEST(Runner, BadOptionsAreInputErrors) {
  RunOptions opt;
  const test::TempDir tmp("runner_bad");
  opt.out_dir = tmp.str();
  opt.quiet = true;
  auto factory = [](const CompiledScene&, BackendKind) { return std::vector<std::unique_ptr<SimulationModel>>{}; };
  auto keyOf = [&](const RunOptions& o) {
    try {
      runScene(oscillatorScene(), o, factory);
    } catch (const InputError& e) {
      return e.key();
    }
    return std::string("<no error>");
  };
  EXPECT_EQ(keyOf(opt), "models");  // no model switched on
  // -1 was once the "not given" value: given, it is refused like any other negative count.
  for (const double s : {-2.0, -1.0, 0.0, std::nan(""), HUGE_VAL}) {
    RunOptions o = opt;
    o.seconds = s;
    EXPECT_EQ(keyOf(o), "--seconds") << s;
  }
  for (const long f : {-1L, 0L, kMaxRunFrames + 1}) {
    RunOptions o = opt;
    o.frames = f;
    EXPECT_EQ(keyOf(o), "--steps") << f;
  }
  RunOptions longest = opt;  // a finite --seconds that needs more than kMaxRunFrames frames
  longest.seconds = 1.0e9;
  EXPECT_EQ(keyOf(longest), "--seconds");
}

TEST(Runner, StepsAndSecondsAreParsedStrictly) {
  EXPECT_EQ(parseRunSteps("1"), 1);
  EXPECT_EQ(parseRunSteps("120"), 120);
  EXPECT_EQ(parseRunSteps(std::to_string(kMaxRunFrames)), kMaxRunFrames);
  // Not silently clamped or wrapped: too large, negative, zero, fractional, signed or not a number.
  for (const char* bad : {"99999999999999999999", "100000001", "-1", "0", "1.5", "+3", " 4", "", "ten"})
    EXPECT_THROW(parseRunSteps(bad), InputError) << bad;
  EXPECT_DOUBLE_EQ(parseRunSeconds("0.5"), 0.5);
  EXPECT_DOUBLE_EQ(parseRunSeconds("2e-3"), 2e-3);
  for (const char* bad : {"-1", "0", "nan", "inf", "1e400", "1s", "", "x"})
    EXPECT_THROW(parseRunSeconds(bad), InputError) << bad;
}

TEST(NumericalGuard, FlagsEnergyGrowthPastTheBound) {
  NumericalGuard g(100.0, 1.0);
  FrameReport r;
  r.kinetic_energy = 2.0;
  EXPECT_TRUE(g.check(r).ok);
  EXPECT_DOUBLE_EQ(g.reference(), 2.0);
  r.kinetic_energy = 150.0;
  EXPECT_TRUE(g.check(r).ok);  // 150 < 100 x 2
  r.kinetic_energy = 250.0;
  GuardVerdict v = g.check(r);
  EXPECT_FALSE(v.ok);
  EXPECT_EQ(v.stage, "energy");
}
