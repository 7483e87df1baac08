// Tests of the runner's haptic loop: a thread beside the simulation with its statistics, none without haptics.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "host/app/runner.h"
#include "host/haptics/bem_global.h"
#include "host/haptics/haptic_loop.h"
#include "host/haptics/hybrid_model.h"
#include "host/haptics/tip_contact.h"
#include "host/io/mesh.h"
#include "host/scene/global_organ_mesh.h"
#include "host/scene/scene_loader.h"
#include "model/input_error.h"
#include "tests/support/repo_paths.h"

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

std::vector<std::unique_ptr<SimulationModel>> slabFactory(const CompiledScene&, BackendKind) {
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
  s.haptics.devices[0].trajectory = trajectory;
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
  ASSERT_EQ(sum.haptic_stats.size(), 1u);
  const PeriodStats& st = sum.haptic_stats[0];
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
  EXPECT_TRUE(sum.haptic_stats.empty());
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

// The model force column of a tick force file (haptic_forces*.txt) as text, one line per tick: hex floats, so
// equal text is equal bits.
std::vector<std::string> modelForceLines(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream f(line);
    std::string tick, t, fx, fy, fz;
    f >> tick >> t >> fx >> fy >> fz;
    out.push_back(fx + " " + fy + " " + fz);
  }
  return out;
}

// The last sample and the model force of the last tick of a recorded hand.
struct LastTick {
  Vec3d position, model_force;
  std::size_t ticks = 0;
};
// The model force of the last tick in a tick force file.
Vec3d lastModelForce(const fs::path& file) {
  const std::vector<std::string> lines = modelForceLines(file);
  if (lines.empty()) return {};
  std::istringstream f(lines.back());
  std::string fx, fy, fz;
  f >> fx >> fy >> fz;
  return {std::strtod(fx.c_str(), nullptr), std::strtod(fy.c_str(), nullptr), std::strtod(fz.c_str(), nullptr)};
}

LastTick lastTick(const fs::path& out, const std::string& name) {
  LastTick r;
  const Trajectory tr = loadTrajectory((out / ("haptic_trajectory_" + name + ".traj")).string());
  r.ticks = tr.samples.size();
  if (!tr.samples.empty()) r.position = tr.samples.back().position_m;
  r.model_force = lastModelForce(out / ("haptic_forces_" + name + ".txt"));
  return r;
}

// Two hands on the slab (top at z = 0.01 m): "left" presses 2 mm at (0.005, 0.005) with a 1 kHz loop, "right"
// 1 mm at (0.015, 0.015) with a 500 Hz loop.
Scene twoHandScene(const fs::path& dir, const std::string& left, const std::string& right,
                   const std::string& playback) {
  Scene s = slabScene("");
  s.haptics.devices_listed = true;
  s.haptics.devices.assign(2, HapticDeviceSpec{});
  s.haptics.devices[0].name = "left";
  s.haptics.devices[0].trajectory = (dir / left).string();
  s.haptics.devices[1].name = "right";
  s.haptics.devices[1].trajectory = (dir / right).string();
  s.haptics.devices[1].rate_hz = 500.0;
  for (auto& d : s.haptics.devices) d.playback = playback;
  s.haptics.has_surface_point = true;
  s.haptics.surface_point_m = {0.0, 0.0, 0.01};
  return s;
}

// Two scripted devices replay two trajectories: the runner starts one loop thread per device, each at its own rate;
// both tick, the summary and summary.txt report each loop's period statistics, metrics.csv has each loop's
// counters (haptic_*, haptic1_*), and each hand's force is its own tool's contact: the MFS tip stiffness times its
// own depth (2 mm and 1 mm; equal to 1e-12 relative), so the left force is twice the right one.
TEST(HapticRunner, TwoScriptedDevicesRunTwoLoopsWithTheirOwnContacts) {
  const fs::path dir = scratch("two");
  std::ofstream(dir / "left.traj") << "0.0 0.005 0.005 0.012 1 0 0 0 0\n0.1 0.005 0.005 0.008 1 0 0 0 1\n";
  std::ofstream(dir / "right.traj") << "0.0 0.015 0.015 0.012 1 0 0 0 0\n0.1 0.015 0.015 0.009 1 0 0 0 1\n";
  const std::uint64_t threads0 = hapticLoopThreadsStarted();
  RunOptions opt;
  opt.frames = 12;
  opt.quiet = true;
  opt.out_dir = (dir / "out").string();
  const Scene scene = twoHandScene(dir, "left.traj", "right.traj", "time");
  const RunSummary sum = runScene(scene, opt, slabFactory);
  EXPECT_EQ(hapticLoopThreadsStarted(), threads0 + 2);
  ASSERT_FALSE(sum.failed) << sum.failure;
  ASSERT_EQ(sum.haptic_stats.size(), 2u);
  for (const PeriodStats& st : sum.haptic_stats) {
    EXPECT_GT(st.ticks, 20u);
    EXPECT_LE(st.p50_s, st.p99_s);
    EXPECT_LE(st.p99_s, st.max_s);
    EXPECT_LE(st.missed, st.ticks);
  }
  EXPECT_DOUBLE_EQ(sum.haptic_stats[0].nominal_s, 1e-3);
  EXPECT_DOUBLE_EQ(sum.haptic_stats[1].nominal_s, 2e-3);
  const std::string summary = readText(fs::path(opt.out_dir) / "summary.txt");
  EXPECT_NE(summary.find("haptic loop left 1000 Hz, device scripted, tool probe"), std::string::npos) << summary;
  EXPECT_NE(summary.find("haptic loop right 500 Hz, device scripted, tool probe"), std::string::npos) << summary;
  const fs::path csv = fs::path(opt.out_dir) / "metrics.csv";
  for (const char* c : {"haptic_hz", "haptic_p50_ms", "haptic_p99_ms", "haptic_max_ms", "haptic1_hz", "haptic1_p50_ms",
                        "haptic1_p99_ms", "haptic1_max_ms", "haptic_force_n", "haptic1_force_n"})
    EXPECT_GT(lastCsvValue(csv, c), 0.0) << c;
  EXPECT_GE(lastCsvValue(csv, "haptic_missed"), 0.0);
  EXPECT_GE(lastCsvValue(csv, "haptic1_missed"), 0.0);
  // Each hand's model force is its own contact: -K (tip - entry point), the entry point on the plane above its tip.
  const TipStiffness k =
      mfsTipStiffness(scene.material, scene.haptics.local_radius_m, scene.haptics.local_spacing_m, Vec3d{0, 0, 1});
  const LastTick left = lastTick(opt.out_dir, "left"), right = lastTick(opt.out_dir, "right");
  ASSERT_NEAR(left.position.z, 0.008, 1e-12);  // both trajectories ended before the run did
  ASSERT_NEAR(right.position.z, 0.009, 1e-12);
  for (const LastTick* h : {&left, &right}) {
    const Vec3d expected = k.handForce(Vec3d{0, 0, h->position.z - 0.01});
    EXPECT_NEAR(norm(h->model_force - expected), 0.0, 1e-12 * norm(expected));
  }
  EXPECT_NEAR(left.model_force.z / right.model_force.z, 2.0, 1e-9);
  fs::remove_all(dir);
}

// Record -> replay of both hands: the trajectories the loops recorded (hex floats), replayed by tick through the
// runner, give every tick's model force bit for bit (the tick force files' text is equal over the common ticks).
// Replaying the right hand's recording with the left hand's tool (swapped) gives other forces: the check can fail.
TEST(HapticRunner, TwoDeviceRecordingReplaysBitExactly) {
  const fs::path dir = scratch("replay");
  std::ofstream(dir / "left.traj") << "0.0 0.005 0.005 0.012 1 0 0 0 0\n0.08 0.006 0.005 0.0085 1 0 0 0 1\n"
                                      "0.16 0.009 0.006 0.008 1 0 0 0 1\n";
  std::ofstream(dir / "right.traj") << "0.0 0.015 0.015 0.012 1 0 0 0 0\n0.1 0.014 0.016 0.0093 1 0 0 0 1\n";
  RunOptions opt;
  opt.frames = 10;
  opt.quiet = true;
  opt.out_dir = (dir / "live").string();
  ASSERT_FALSE(runScene(twoHandScene(dir, "left.traj", "right.traj", "time"), opt, slabFactory).failed);
  const fs::path live(opt.out_dir);
  opt.out_dir = (dir / "replay").string();
  ASSERT_FALSE(runScene(twoHandScene(live, "haptic_trajectory_left.traj", "haptic_trajectory_right.traj", "tick"), opt,
                        slabFactory)
                   .failed);
  const fs::path replay(opt.out_dir);
  for (const char* name : {"left", "right"}) {
    SCOPED_TRACE(name);
    const std::vector<std::string> a = modelForceLines(live / ("haptic_forces_" + std::string(name) + ".txt"));
    const std::vector<std::string> b = modelForceLines(replay / ("haptic_forces_" + std::string(name) + ".txt"));
    const std::size_t n = std::min(a.size(), b.size());
    ASSERT_GT(n, 60u);
    std::size_t in_contact = 0;
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_EQ(a[i], b[i]) << "tick " << i;
      in_contact += a[i] != "0x0p+0 0x0p+0 0x0p+0";
    }
    EXPECT_GT(in_contact, 10u);  // the compared forces include contact, not only zeros
  }
  opt.out_dir = (dir / "swapped").string();
  ASSERT_FALSE(runScene(twoHandScene(live, "haptic_trajectory_right.traj", "haptic_trajectory_left.traj", "tick"), opt,
                        slabFactory)
                   .failed);
  const std::vector<std::string> a = modelForceLines(live / "haptic_forces_left.txt");
  const std::vector<std::string> b = modelForceLines(fs::path(opt.out_dir) / "haptic_forces_left.txt");
  std::size_t differ = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) differ += a[i] != b[i];
  EXPECT_GT(differ, 10u);
  fs::remove_all(dir);
}

// global_model "bem" through the runner: the organ (an icosphere of radius 5 cm, 80 elements, resting on a fixed box
// around its bottom) is precomputed once, cached, and the tip pressed 2 mm into its top element feels the hybrid
// coupling's force (HybridHapticModel touch + localTick on the same organ: 1e-9 relative), softer than the local
// model with its boundary held; the global model steps once per frame (metrics: one contact, the organ surface
// moved by the tip's 2 mm), the deformed organ is written, and a second run loads the cache and feels the same.
TEST(HapticRunner, GlobalBemModelGivesTheHybridCouplingsForce) {
  const fs::path dir = scratch("bem");
  const TriangleMesh mesh = icosphereMesh(0.05, 1);
  writeObj((dir / "organ.obj").string(), mesh);
  BemModel bem(mesh, {3e3, 0.45});
  int top = 0;
  for (int j = 0; j < bem.elementCount(); ++j)
    if (bem.centroids()[j].z > bem.centroids()[top].z) top = j;
  const Vec3d c = bem.centroids()[top], n = bem.normals()[top];
  {
    std::ofstream t(dir / "press.traj");
    t.precision(17);
    for (const auto& [time, depth] : {std::pair{0.0, -2e-3}, std::pair{0.1, 2e-3}}) {
      const Vec3d p = c - n * depth;
      t << time << ' ' << p.x << ' ' << p.y << ' ' << p.z << " 1 0 0 0 0\n";
    }
  }
  Scene s = slabScene((dir / "press.traj").string());
  s.fixed = {FixedRegion{{-1, -1, -1}, {1, 1, -0.035}}};
  s.haptics.global_model = "bem";
  s.haptics.global_mesh = (dir / "organ.obj").string();
  s.haptics.global_cache = (dir / "organ.bemcache").string();
  s.haptics.has_surface_point = true;
  s.haptics.surface_point_m = c;
  s.haptics.surface_normal = n;
  RunOptions opt;
  opt.frames = 12;
  opt.quiet = true;
  opt.out_dir = (dir / "first").string();
  const RunSummary first = runScene(s, opt, slabFactory);
  ASSERT_FALSE(first.failed) << first.failure;
  EXPECT_NE(first.haptic.find("global model bem: 80 elements (240 DOFs), built"), std::string::npos) << first.haptic;
  EXPECT_TRUE(fs::exists(dir / "organ.bemcache"));

  // The same organ by hand: the BEM model, its supports, the tip's local model, the contact at the top element.
  const std::vector<BemBc> supports = organSupports(mesh, s.fixed);
  bem.factorBase(supports);
  HemisphereCloudSpec local;
  local.inner_spacing_m = s.haptics.local_spacing_m;
  local.inner_shells = 2;
  local.radius_m = s.haptics.local_radius_m;
  HybridHapticModel hybrid(bem, local, Material{3e3, 0.45});
  hybrid.touch(top);
  const Vec3d d = n * -2e-3;
  hybrid.globalStep(d, 0.0);
  const Vec3d expected = hybrid.localTick(d).force_n;
  const Vec3d model_force = lastModelForce(fs::path(opt.out_dir) / "haptic_forces.txt");
  EXPECT_LE(norm(model_force - expected), 1e-9 * norm(expected)) << model_force.z << " vs " << expected.z;
  EXPECT_LT(dot(model_force, n), dot(hybrid.localOnlyForce(d), n));  // the organ gives: softer than held
  const fs::path csv = fs::path(opt.out_dir) / "metrics.csv";
  EXPECT_EQ(lastCsvValue(csv, "haptic_organ_contacts"), 1.0);
  EXPECT_NEAR(lastCsvValue(csv, "haptic_organ_max_displacement_m"), 2e-3, 1e-3);  // at least the tip's 2 mm
  EXPECT_GE(lastCsvValue(csv, "haptic_organ_max_displacement_m"), 2e-3 * (1 - 1e-6));
  const TriangleMesh deformed = loadMesh((fs::path(opt.out_dir) / "final_haptic_organ_surface.obj").string());
  ASSERT_EQ(deformed.vertices.size(), mesh.vertices.size());
  // Each vertex of the pressed element moves by the mean of its (5 or 6) elements: at least its sixth of the tip's
  // 2 mm inward, its neighbours pressed in as well.
  for (int v : mesh.triangles[std::size_t(top)])
    EXPECT_GT(dot(mesh.vertices[std::size_t(v)] - deformed.vertices[std::size_t(v)], n), 2e-3 / 6.0) << "vertex " << v;

  opt.out_dir = (dir / "second").string();
  const RunSummary second = runScene(s, opt, slabFactory);
  ASSERT_FALSE(second.failed) << second.failure;
  EXPECT_NE(second.haptic.find("loaded from the cache"), std::string::npos) << second.haptic;
  const Vec3d again = lastModelForce(fs::path(opt.out_dir) / "haptic_forces.txt");
  EXPECT_LE(norm(again - expected), 1e-9 * norm(expected));
  fs::remove_all(dir);
}

// `incision run scenes/haptic_cut_block.json`: the shipped haptic cutting scene, through the runner with the
// model factory (CPU): the loop's cut decisions reach the dissection model between frames and cut the block in
// two (metrics.csv's last row), the summary reports the loop and the decisions.
TEST(HapticRunner, ShippedHapticCuttingSceneCutsTheBlock) {
  const fs::path dir = scratch("cut");
  Scene s = loadSceneFile(test::sourcePath("scenes/haptic_cut_block.json"));
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
