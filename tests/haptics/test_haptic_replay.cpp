// Record -> replay of a haptic cutting session: the same forces and the same topology, bit for bit (CPU backend).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <string>

#include "tests/support/haptic_replay_fixture.h"

namespace inc {
namespace {

using namespace hapticreplay;

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
  const TopologySummary &first = rec.frames.front().topology, &last = rec.frames.back().topology;
  EXPECT_EQ(last.cuts_applied, 1);
  EXPECT_NE(last.particles, first.particles);
  EXPECT_NE(last.links, first.links);
  EXPECT_GT(last.surface_triangles, first.surface_triangles);  // the surface was split and capped
  double fmax = 0.0;
  for (const TickRecord& t : rec.ticks) fmax = std::max(fmax, norm(t.force_n));
  EXPECT_GT(fmax, 0.02);  // the blade pressed past F_p
  std::printf(
      "recorded: %zu ticks, %zu frames, spheres %zu -> %zu, links %zu -> %zu, surface triangles %zu -> %zu, "
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
  for (std::size_t i = 0; i < rec.ticks.size(); ++i)
    forces_differ |= !sameBits(alt.ticks[i].force_n, rec.ticks[i].force_n);
  EXPECT_TRUE(forces_differ);
  EXPECT_FALSE(alt.frames.back().topology == rec.frames.back().topology);
  std::filesystem::remove_all(path.parent_path());
}

}  // namespace
}  // namespace inc
