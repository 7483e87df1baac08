// Record -> replay of a haptic cutting session on the CUDA backend: the same forces and topology, bit for bit.
#if INCISION_HAVE_CUDA
#include <gtest/gtest.h>

#include <cstring>

#include "kernels/device_info.h"
#include "tests/support/haptic_replay_fixture.h"

using namespace inc;
using namespace inc::hapticreplay;

namespace {

bool noDevice() { return inc::cuda::queryDevices().device_count == 0; }

// The recorded trajectory replayed by tick on a fresh CUDA model (float32 and float64): forces and every
// frame's topology summary (counts and the hash of the particle and surface positions) are identical.
TEST(HapticReplayGpu, RecordedCuttingSessionReplaysBitExactlyOnCuda) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  for (Precision precision : {Precision::Float32, Precision::Float64}) {
    ScriptedDevice authored(authoredStroke(), ScriptedDevice::Mode::kByTime, 3.3);
    const SessionRun rec = runSession(authored, 40, BackendKind::Cuda, precision);
    ASSERT_TRUE(rec.messages.empty()) << rec.messages.front();
    EXPECT_EQ(rec.frames.back().topology.cuts_applied, 1);
    EXPECT_NE(rec.frames.back().topology.particles, rec.frames.front().topology.particles);
    ScriptedDevice replay(rec.recorded, ScriptedDevice::Mode::kByTick, 3.3);
    const SessionRun rep = runSession(replay, 40, BackendKind::Cuda, precision);
    ASSERT_EQ(rep.ticks.size(), rec.ticks.size());
    for (std::size_t i = 0; i < rec.ticks.size(); ++i)
      ASSERT_EQ(std::memcmp(&rep.ticks[i].force_n, &rec.ticks[i].force_n, sizeof(Vec3d)), 0) << "tick " << i;
    ASSERT_EQ(rep.frames.size(), rec.frames.size());
    for (std::size_t f = 0; f < rec.frames.size(); ++f)
      EXPECT_TRUE(rep.frames[f].topology == rec.frames[f].topology) << "frame " << f;
  }
}

}  // namespace
#endif
