// Every shipped scene as a regression test on the CPU: a run of it meets the physical bounds of its row in
// tests/support/shipped_scene_table.h, and no scene ships without a row.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "tests/support/repo_paths.h"
#include "tests/support/shipped_scene_run.h"
#include "tests/support/shipped_scene_table.h"

namespace inc {
namespace {

class ShippedScene : public ::testing::TestWithParam<test::ShippedSceneBounds> {};

TEST_P(ShippedScene, MeetsItsPhysicalBoundsOnTheCpu) {
  const test::ShippedSceneBounds& row = GetParam();
  const test::ShippedSceneRecord rec = test::runShippedScene(row, BackendKind::Cpu);
  std::printf("%s (cpu): %s\n", row.scene, test::shippedSceneMeasured(rec).c_str());
  const std::vector<std::string> failures = test::shippedSceneFailures(row, rec);
  EXPECT_TRUE(failures.empty()) << row.scene << ": " << test::joinedFailures(failures);
}

INSTANTIATE_TEST_SUITE_P(Scenes, ShippedScene, ::testing::ValuesIn(test::shippedSceneBounds()),
                         [](const ::testing::TestParamInfo<test::ShippedSceneBounds>& p) { return p.param.scene; });

// A scene added to scenes/ without a row of bounds would ship untested; a row whose scene is gone tests nothing.
TEST(ShippedScenes, EverySceneFileHasBoundsAndEveryRowAScene) {
  std::set<std::string> files, rows;
  for (const auto& e : std::filesystem::directory_iterator(test::sourcePath("scenes")))
    if (e.path().extension() == ".json") files.insert(e.path().stem().string());
  for (const test::ShippedSceneBounds& row : test::shippedSceneBounds()) {
    EXPECT_TRUE(rows.insert(row.scene).second) << row.scene << " has two rows";
  }
  EXPECT_FALSE(files.empty()) << "no scenes found under " << test::sourcePath("scenes");
  for (const std::string& f : files)
    EXPECT_TRUE(rows.count(f)) << "scenes/" << f
                               << ".json has no row in tests/support/shipped_scene_table.h: add its physical bounds";
  for (const std::string& r : rows)
    EXPECT_TRUE(files.count(r)) << "tests/support/shipped_scene_table.h has a row for scenes/" << r
                                << ".json, which does not exist";
}

}  // namespace
}  // namespace inc
