// Record -> replay of a haptic cutting session: the same forces and the same topology, bit for bit (CPU backend).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <string>

#include "host/dissection_simulation.h"
#include "host/haptics/haptic_cut_session.h"
#include "host/haptics/mfs_local.h"

namespace inc {
namespace {

// A 6 x 4 x 3 cm block of 1 cm metaballs without gravity, cut only by the haptic device (no scripted
// scalpel); the cutting thresholds come from the scene's material.
Scene blockScene() {
  Scene s;
  s.file = "<test:haptic_block>";
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.size = Vec3d(0.06, 0.04, 0.03);
  s.geometry.spacing = 0.01;
  s.models.pbd_metaballs = true;
  s.models.cutting = true;
  s.models.haptics = true;
  s.solver.gravity = Vec3d(0, 0, 0);
  s.solver.substeps = 2;
  s.pbd.iterations = 5;
  s.material.youngs_modulus = 3e3;
  s.material.cutting.press_n = 0.02;     // F_p
  s.material.cutting.static_n = 0.008;   // F_s
  s.material.cutting.dynamic_n = 0.004;  // F_d
  s.material.cutting.friction_per_depth_n_per_m = 5.0;
  return s;
}

// The local MFS model alone (tool tip prescribed, outer shell held): force on the hand for a tip
// displacement, frame = world (the block's top face has the outward normal +z).
struct TipModel {
  std::unique_ptr<MfsLocalModel> m;
  Eigen::VectorXd zero;
  TipModel() {
    HemisphereCloudSpec spec;
    spec.inner_spacing_m = 2e-3;
    spec.inner_shells = 2;
    spec.radius_m = 8e-3;
    HemisphereCloud cc = hemisphereCloud(spec);
    cc.cloud.singular[0] = 1;
    const int N = int(cc.cloud.nodes.size());
    std::vector<DofRole> roles(3 * N, DofRole::kFree);
    for (int k = 0; k < 3; ++k) roles[k] = DofRole::kPrescribed;
    for (int i = 1; i < N; ++i)
      if (cc.node_shell[i] == int(cc.shell_r_m.size()) - 1)
        for (int k = 0; k < 3; ++k) roles[3 * i + k] = DofRole::kCoupled;
    m = std::make_unique<MfsLocalModel>(cc.cloud, MfsMaterial{3e3, 0.45});
    m->setRoles(roles, false);
    zero = Eigen::VectorXd::Zero(Eigen::Index(m->coupledDofs().size()));
  }
  ForceResult operator()(const Vec3d& d) const {
    const Eigen::VectorXd f = m->reactionForce(Eigen::Vector3d(d.x, d.y, d.z), zero);
    ForceResult r;
    r.force_n = Vec3d{-f[0], -f[1], -f[2]};
    return r;
  }
};

// The scalpel: above the block 0.5 mm inside its -x end, pressed 4 mm in, drawn along +x past the far end
// (the cut starts once the elastic drag passes F_s, about 1 mm on, so the stroke spans the whole section),
// halted (the friction vanishes: stop -> the cut is applied), lifted.
Trajectory authoredStroke() {
  Trajectory tr;
  auto add = [&](double t, double x, double z) {
    DeviceSample s;
    s.t_s = t;
    s.position_m = {x, 0.002, z};
    tr.samples.push_back(s);
  };
  const double top = 0.015;
  add(0.0, -0.0295, top + 0.003);
  add(0.1, -0.0295, top - 0.004);
  add(0.5, 0.045, top - 0.004);
  add(0.6, 0.045, top - 0.004);
  add(0.7, 0.045, top + 0.003);
  return tr;
}

struct SessionRun {
  std::vector<TickRecord> ticks;
  std::vector<SessionFrame> frames;
  Trajectory recorded;
  std::vector<std::string> messages;
};

SessionRun runSession(HapticDevice& device, int frames) {
  const Scene scene = blockScene();
  auto sim = makeDissectionSimulation(scene, BackendKind::Cpu, Precision::Float64);
  const TipModel tip;
  CuttingTool tool([&tip](const Vec3d& d) { return tip(d); }, scene.material.cutting, Vec3d{0, 0, 0.015},
                   Vec3d{0, 0, 1});
  HapticCutSessionConfig cfg;
  cfg.frame_dt_s = 0.02;
  cfg.blade_length_m = 0.08;  // vertical blade through the whole block height
  HapticCutSession session(*sim, device, tool, cfg);
  session.runFrames(frames);
  SessionRun r;
  r.ticks = session.loop().records();
  r.frames = session.frames();
  r.recorded = session.loop().recordedTrajectory();
  r.messages = session.messages();
  return r;
}

std::filesystem::path scratchDir() {
  const auto d = std::filesystem::temp_directory_path() / ("incision_replay_" + std::to_string(::getpid()));
  std::filesystem::create_directories(d);
  return d;
}

bool sameBits(const Vec3d& a, const Vec3d& b) { return std::memcmp(&a, &b, sizeof(Vec3d)) == 0; }

TEST(HapticReplay, RecordedCuttingSessionReplaysForcesAndTopologyBitExactly) {
  const int frames = 40;  // 0.8 s: the whole stroke
  ScriptedDevice authored(authoredStroke(), ScriptedDevice::Mode::kByTime, 3.3);
  const SessionRun rec = runSession(authored, frames);
  ASSERT_TRUE(rec.messages.empty()) << rec.messages.front();

  // The session really cut: decisions went to the pipeline, a cut was applied, the topology changed.
  int events = 0, applied = 0;
  std::string event_frames;
  for (std::size_t f = 0; f < rec.frames.size(); ++f) {
    events += rec.frames[f].cut_events;
    applied += rec.frames[f].cut_applied ? 1 : 0;
    if (rec.frames[f].cut_events) event_frames += " " + std::to_string(f);
  }
  EXPECT_EQ(events, 2);  // one start, one stop
  EXPECT_EQ(applied, 1);
  const TopologySummary& first = rec.frames.front().topology, &last = rec.frames.back().topology;
  EXPECT_EQ(last.cuts_applied, 1);
  EXPECT_NE(last.particles, first.particles);
  EXPECT_NE(last.links, first.links);
  EXPECT_GT(last.surface_triangles, first.surface_triangles);  // the surface was split and capped
  double fmax = 0.0;
  for (const TickRecord& t : rec.ticks) fmax = std::max(fmax, norm(t.force_n));
  EXPECT_GT(fmax, 0.02);  // the blade pressed past F_p
  std::printf("recorded: %zu ticks, %zu frames, spheres %zu -> %zu, links %zu -> %zu, surface triangles %zu -> %zu, "
              "max force %.4f N, cut decisions in frames%s\n",
              rec.ticks.size(), rec.frames.size(), first.particles, last.particles, first.links, last.links,
              first.surface_triangles, last.surface_triangles, fmax, event_frames.c_str());

  // Record to a file (hex floats), read it back, replay by tick on a fresh model.
  const auto path = scratchDir() / "stroke.traj";
  writeTrajectory(path.string(), rec.recorded);
  ScriptedDevice replay(loadTrajectory(path.string()), ScriptedDevice::Mode::kByTick, 3.3);
  const SessionRun rep = runSession(replay, frames);
  ASSERT_EQ(rep.ticks.size(), rec.ticks.size());
  for (std::size_t i = 0; i < rec.ticks.size(); ++i) {
    ASSERT_TRUE(sameBits(rep.ticks[i].model_force_n, rec.ticks[i].model_force_n)) << "tick " << i;
    ASSERT_TRUE(sameBits(rep.ticks[i].force_n, rec.ticks[i].force_n)) << "tick " << i;
  }
  ASSERT_EQ(rep.frames.size(), rec.frames.size());
  for (std::size_t f = 0; f < rec.frames.size(); ++f) {
    EXPECT_EQ(rep.frames[f].cut_events, rec.frames[f].cut_events) << "frame " << f;
    EXPECT_TRUE(rep.frames[f].topology == rec.frames[f].topology) << "frame " << f;
  }

  // The comparison can fail: the same replay with the blade drawn 0.1 mm further along +y gives other forces
  // (the drag before the cut starts) and another cut (the surface is split elsewhere).
  Trajectory shifted = loadTrajectory(path.string());
  for (DeviceSample& s : shifted.samples) s.position_m.y += 1e-4 * s.t_s;
  ScriptedDevice other(shifted, ScriptedDevice::Mode::kByTick, 3.3);
  const SessionRun alt = runSession(other, frames);
  bool forces_differ = false;
  for (std::size_t i = 0; i < rec.ticks.size(); ++i) forces_differ |= !sameBits(alt.ticks[i].force_n, rec.ticks[i].force_n);
  EXPECT_TRUE(forces_differ);
  EXPECT_FALSE(alt.frames.back().topology == rec.frames.back().topology);
  std::filesystem::remove_all(path.parent_path());
}

}  // namespace
}  // namespace inc
