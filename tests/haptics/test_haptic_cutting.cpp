// Tests of the cutting force model (eqs. 15-16): decomposition, state machine with hysteresis, friction.
#include <gtest/gtest.h>

#include <vector>

#include "host/haptics/cutting_force_model.h"
#include "model/input_error.h"

namespace inc {
namespace {

TEST(HapticCutting, DecompositionIsOrthogonalAndComplete) {
  const Vec3d n = Vec3d{1.0, 2.0, 2.0} * (1.0 / 3.0);
  const Vec3d f{0.3, -1.2, 2.5};
  const ForceSplit<double> s = decomposeForce(f, n);
  const Vec3d sum = s.normal + s.tangential;
  EXPECT_NEAR(norm(sum - f), 0.0, 1e-15);             // eq. 15
  EXPECT_NEAR(dot(s.tangential, n), 0.0, 1e-15);      // f_t in the tangent plane
  EXPECT_NEAR(norm(cross(s.normal, n)), 0.0, 1e-15);  // f_n along n
  EXPECT_NEAR(dot(s.normal, n), (0.3 - 2.4 + 5.0) / 3.0, 1e-15);
}

TEST(HapticCutting, StateMachineFollowsScriptedProfile) {
  CutThresholds<double> th;  // F_p = 1, F_s = 0.6, F_d = 0.3
  CuttingForceModel model(th);
  const Vec3d n{0, 0, 1}, v{0.01, 0, 0};
  struct Step {
    double fn, ft, depth;
    CutState want;
    bool start, stop;
  };
  // Press (not through), press through, drag below F_s, above F_s (cut), inside the hysteresis band
  // (keeps cutting), below F_d (stop), inside the band (stays stopped), above F_s (restart), lift off.
  const std::vector<Step> profile = {
      {0.0, 0.0, 0.0, CutState::kIdle, false, false},      {0.5, 0.0, 1e-3, CutState::kPressing, false, false},
      {0.5, 0.9, 1e-3, CutState::kPressing, false, false}, {1.2, 0.0, 2e-3, CutState::kPressing, false, false},
      {1.2, 0.5, 2e-3, CutState::kPressing, false, false}, {1.2, 0.7, 2e-3, CutState::kCutting, true, false},
      {1.2, 0.45, 2e-3, CutState::kCutting, false, false}, {1.2, 0.31, 2e-3, CutState::kCutting, false, false},
      {1.2, 0.29, 2e-3, CutState::kStopped, false, true},  {1.2, 0.5, 2e-3, CutState::kStopped, false, false},
      {1.2, 0.61, 2e-3, CutState::kCutting, true, false},  {0.0, 0.0, 0.0, CutState::kIdle, false, true},
      {0.5, 0.9, 1e-3, CutState::kPressing, false, false},  // entry latch was cleared by lifting off
  };
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const Step& s = profile[i];
    const CutForceOutput o = model.tick(Vec3d{s.ft, 0.0, -s.fn}, n, v, s.depth);
    EXPECT_EQ(o.machine.state, s.want) << "step " << i;
    EXPECT_EQ(o.machine.start_cut, s.start) << "step " << i;
    EXPECT_EQ(o.machine.stop_cut, s.stop) << "step " << i;
    if (s.want != CutState::kCutting) {
      EXPECT_EQ(norm(o.friction_n), 0.0) << "step " << i;
    } else {
      EXPECT_NEAR(norm(o.friction_n), th.friction_per_depth_n_per_m * s.depth, 1e-12) << "step " << i;
    }
  }
}

TEST(HapticCutting, FrictionOpposesMotionProportionalToDepth) {
  const Vec3d n{0, 0, 1};
  const double k = 250.0;  // N/m
  for (double depth : {1e-3, 2e-3, 4e-3}) {
    const Vec3d v{0.03, -0.04, 0.2};  // normal part must not matter
    const Vec3d f = cuttingFriction(v, n, depth, k);
    EXPECT_NEAR(norm(f), k * depth, 1e-12);
    EXPECT_NEAR(f.x, -k * depth * 0.6, 1e-12);
    EXPECT_NEAR(f.y, k * depth * 0.8, 1e-12);
    EXPECT_NEAR(f.z, 0.0, 1e-15);
  }
  EXPECT_EQ(norm(cuttingFriction(Vec3d{0, 0, 0.1}, n, 1e-3, k)), 0.0);   // no tangential motion
  EXPECT_EQ(norm(cuttingFriction(Vec3d{0.1, 0, 0}, n, -1e-3, k)), 0.0);  // out of tissue
}

TEST(HapticCutting, BadThresholdsAreInputErrors) {
  CutThresholds<double> th;
  th.dynamic_n = 0.7;  // above F_s: no hysteresis possible
  EXPECT_THROW(CuttingForceModel m(th), InputError);
  th = CutThresholds<double>{};
  th.press_n = -1.0;
  EXPECT_THROW(CuttingForceModel m(th), InputError);
}

}  // namespace
}  // namespace inc
