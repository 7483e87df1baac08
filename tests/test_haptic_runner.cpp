// Tests of the runner's haptic loop: a thread beside the simulation with its statistics, none without haptics.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "host/haptics/haptic_loop.h"
#include "host/input_error.h"
#include "host/runner.h"
#include "host/scene_loader.h"
#include "test_paths.h"

namespace inc {
namespace {
namespace fs = std::filesystem;

// A resting slab of particles (no surface: the tissue plane is found from the particles, its top at z = 0.01 m).
class RestingSlab : public SimulationModel {
 public:
  RestingSlab() {
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j)
        for (int k = 0; k < 3; ++k) x_.push_back({0.005 * i, 0.005 * j, 0.005 * k});
  }
  std::string name() const override { return "slab"; }
  BackendKind backend() const override { return BackendKind::Cpu; }
  std::size_t particleCount() const override { return x_.size(); }
  FrameReport advance(double frame_dt) override {
    FrameReport r;
    r.substeps = 1;
    r.dt = frame_dt;
    r.stages = {{"rest", 0.0}};
    return r;
  }
  void saveCheckpoint() override {}
  void restoreCheckpoint() override {}
  void scaleTimeStep(double) override {}
  void currentPositions(std::vector<Vec3d>& out) const override { out = x_; }
  MemoryReport memory() const override { return {0, x_.size() * sizeof(Vec3d)}; }

 private:
  std::vector<Vec3d> x_;
};

std::vector<std::unique_ptr<SimulationModel>> slabFactory(const Scene&, BackendKind) {
  std::vector<std::unique_ptr<SimulationModel>> v;
  v.push_back(std::make_unique<RestingSlab>());
  return v;
}

fs::path scratch(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("incision_haptic_runner_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// metrics.csv: the header's columns and the last row's values.
double lastCsvValue(const fs::path& csv, const std::string& column) {
  std::ifstream in(csv);
  std::string header, line, last;
  std::getline(in, header);
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  std::vector<std::string> names, values;
  for (std::stringstream h(header); std::getline(h, line, ',');) names.push_back(line);
  for (std::stringstream v(last); std::getline(v, line, ',');) values.push_back(line);
  for (std::size_t i = 0; i < names.size() && i < values.size(); ++i)
    if (names[i] == column) return std::stod(values[i]);
  return -1.0;
}

Scene slabScene(const std::string& trajectory) {
  Scene s;
  s.name = "slab";
  s.file = "<test:haptic_slab>";
  s.models.mls = true;  // the factory ignores it; a scene needs a deformable model
  s.models.haptics = true;
  s.solver.frame_dt = 0.02;
  s.haptics.trajectory = trajectory;
  s.haptics.record_trajectory = true;
  return s;
}

// A probe scene: the runner starts one haptic loop thread, runs it at 1 kHz while the frames step, and reports
// its statistics (p50 <= p99 <= max, missed within the ticks: bookkeeping, not timing) in the summary line and
// summary.txt, the counters haptic_hz / haptic_p99_ms in metrics.csv, and the device trajectory it recorded.
TEST(HapticRunner, ProbeSceneRunsTheLoopBesideTheSimulation) {
  const fs::path dir = scratch("probe");
  {
    std::ofstream t(dir / "press.traj");
    t << "0.0 0.01 0.01 0.012 1 0 0 0 0\n0.1 0.01 0.01 0.008 1 0 0 0 1\n";  // into the slab's top by 2 mm
  }
  const std::uint64_t threads0 = hapticLoopThreadsStarted();
  RunOptions opt;
  opt.frames = 12;
  opt.quiet = true;
  opt.out_dir = (dir / "out").string();
  const RunSummary sum = runScene(slabScene((dir / "press.traj").string()), opt, slabFactory);
  EXPECT_EQ(hapticLoopThreadsStarted(), threads0 + 1);
  ASSERT_FALSE(sum.failed) << sum.failure;
  const PeriodStats& st = sum.haptic_stats;
  EXPECT_GT(st.ticks, 1u);
  EXPECT_GT(st.p50_s, 0.0);
  EXPECT_LE(st.p50_s, st.p99_s);
  EXPECT_LE(st.p99_s, st.max_s);
  EXPECT_LE(st.missed, st.ticks);
  EXPECT_NE(sum.line().find("haptic loop 1000 Hz, device scripted"), std::string::npos) << sum.line();
  EXPECT_EQ(sum.line().find("cut decisions"), std::string::npos);  // a probe does not cut
  const std::string summary = readText(fs::path(opt.out_dir) / "summary.txt");
  EXPECT_NE(summary.find("haptic loop 1000 Hz"), std::string::npos) << summary;
  EXPECT_GT(lastCsvValue(fs::path(opt.out_dir) / "metrics.csv", "haptic_hz"), 0.0);
  EXPECT_GT(lastCsvValue(fs::path(opt.out_dir) / "metrics.csv", "haptic_p99_ms"), 0.0);
  const Trajectory rec = loadTrajectory((fs::path(opt.out_dir) / "haptic_trajectory.traj").string());
  EXPECT_EQ(rec.samples.size(), st.ticks);
  std::printf("%s\n", sum.haptic.c_str());
  fs::remove_all(dir);
}

// Without models.haptics nothing of it is built: no loop thread, no haptic line, no haptic counters, and the
// memory is the model's alone.
TEST(HapticRunner, SceneWithoutHapticsStartsNoHapticThread) {
  const fs::path dir = scratch("none");
  Scene s = slabScene("");
  s.models.haptics = false;
  const std::uint64_t threads0 = hapticLoopThreadsStarted();
  RunOptions opt;
  opt.frames = 3;
  opt.quiet = true;
  opt.out_dir = (dir / "out").string();
  const RunSummary sum = runScene(s, opt, slabFactory);
  EXPECT_EQ(hapticLoopThreadsStarted(), threads0);
  EXPECT_TRUE(sum.haptic.empty());
  EXPECT_EQ(sum.haptic_stats.ticks, 0u);
  EXPECT_EQ(sum.line().find("haptic"), std::string::npos) << sum.line();
  EXPECT_EQ(readText(fs::path(opt.out_dir) / "metrics.csv").find("haptic"), std::string::npos);
  EXPECT_EQ(sum.memory.host_bytes, RestingSlab().memory().host_bytes);
  fs::remove_all(dir);
}

// A scripted device needs its trajectory: an InputError naming the scene file and haptics.trajectory, before any
// loop starts.
TEST(HapticRunner, ScriptedDeviceWithoutTrajectoryIsAnInputError) {
  const fs::path dir = scratch("bad");
  const std::uint64_t threads0 = hapticLoopThreadsStarted();
  RunOptions opt;
  opt.frames = 2;
  opt.quiet = true;
  opt.out_dir = (dir / "out").string();
  try {
    runScene(slabScene(""), opt, slabFactory);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "<test:haptic_slab>");
    EXPECT_EQ(e.key(), "haptics.trajectory");
  }
  Scene s = slabScene((dir / "absent.traj").string());
  try {
    runScene(s, opt, slabFactory);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "haptics.trajectory");
    EXPECT_NE(e.reason().find("absent.traj"), std::string::npos) << e.what();
  }
  EXPECT_EQ(hapticLoopThreadsStarted(), threads0);
  fs::remove_all(dir);
}

// `incision run scenes/haptic_cut_block.json`: the shipped haptic cutting scene, through the runner with the
// model factory (CPU): the loop's cut decisions reach the dissection model between frames and cut the block in
// two (metrics.csv's last row), the summary reports the loop and the decisions.
TEST(HapticRunner, ShippedHapticCuttingSceneCutsTheBlock) {
  const fs::path dir = scratch("cut");
  Scene s = loadSceneFile(std::string(INCISION_SOURCE_DIR) + "/scenes/haptic_cut_block.json");
  s.output.particles_ply = s.output.mesh_obj = false;
  RunOptions opt;
  opt.backend = BackendKind::Cpu;
  opt.quiet = true;
  opt.out_dir = (dir / "out").string();
  const RunSummary sum = runScene(s, opt);
  ASSERT_FALSE(sum.failed) << sum.failure;
  EXPECT_EQ(sum.frames_done, 40);
  const fs::path csv = fs::path(opt.out_dir) / "metrics.csv";
  EXPECT_EQ(lastCsvValue(csv, "cuts_applied"), 1.0) << sum.line();
  EXPECT_EQ(lastCsvValue(csv, "sphere_components"), 2.0);
  EXPECT_EQ(lastCsvValue(csv, "haptic_cut_decisions"), 2.0);
  EXPECT_NE(sum.line().find("cut decisions 2, cuts applied 1"), std::string::npos) << sum.line();
  std::printf("%s\n", sum.haptic.c_str());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace inc
