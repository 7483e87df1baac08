// Every shipped scene on CUDA: the same runs and physical bounds as tests/app/test_shipped_scenes.cpp on the CPU
// (tests/support/shipped_scene_table.h); skipped without a GPU.
#include <gtest/gtest.h>

#if INCISION_HAVE_CUDA

#include <string>
#include <vector>

#include "kernels/device_info.h"
#include "tests/support/shipped_scene_run.h"
#include "tests/support/shipped_scene_table.h"

namespace inc {
namespace {

class ShippedSceneGpu : public ::testing::TestWithParam<test::ShippedSceneBounds> {};

TEST_P(ShippedSceneGpu, MeetsItsPhysicalBoundsOnCuda) {
  if (cuda::queryDevices().device_count == 0) GTEST_SKIP() << "no CUDA device";
  const test::ShippedSceneBounds& row = GetParam();
  const test::ShippedSceneRecord rec = test::runShippedScene(row, BackendKind::Cuda);
  std::printf("%s (cuda): %s\n", row.scene, test::shippedSceneMeasured(rec).c_str());
  const std::vector<std::string> failures = test::shippedSceneFailures(row, rec);
  EXPECT_TRUE(failures.empty()) << row.scene << ": " << test::joinedFailures(failures);
}

INSTANTIATE_TEST_SUITE_P(Scenes, ShippedSceneGpu, ::testing::ValuesIn(test::shippedSceneBounds()),
                         [](const ::testing::TestParamInfo<test::ShippedSceneBounds>& p) { return p.param.scene; });

}  // namespace
}  // namespace inc

#endif  // INCISION_HAVE_CUDA
