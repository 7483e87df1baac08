// The bring-your-own-organ corpus on the CPU (issue 31): every corpus mesh, with the scene a user would write and
// every other key at its default, is grasped, cut straight and cut along a curve through `incision run`'s runner;
// the run must end and keep a closed, right-side-out surface of nearly its rest volume. Open meshes are refused.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <tuple>

#include "model/input_error.h"
#include "tests/support/organ_corpus.h"
#include "tests/support/repo_paths.h"

namespace inc {
namespace {

// The surface volume may drift this far from the rest volume (issue 31: "within a few per cent").
constexpr double kVolumeTolerance = 0.05;

using CorpusCase = std::tuple<std::size_t, test::CorpusAction>;

class OrganCorpus : public ::testing::TestWithParam<CorpusCase> {};

TEST_P(OrganCorpus, RunsToTheEndWithAClosedSurfaceOfItsVolume) {
  const test::CorpusMesh& cm = test::corpusMeshes()[std::get<0>(GetParam())];
  const test::CorpusAction action = std::get<1>(GetParam());
  const test::CorpusResult r = test::runCorpusCase(cm, action, BackendKind::Cpu);
  if (r.skipped) GTEST_SKIP() << r.skip_reason;
  const std::vector<std::string> failures = test::corpusFailures(r, action, kVolumeTolerance);
  std::printf("[ corpus ] %s\n", test::corpusRow(cm, action, r, failures.empty() ? "ok" : failures.front()).c_str());
  for (const std::string& f : failures) ADD_FAILURE() << cm.name << " " << test::actionName(action) << ": " << f;
}

std::string caseName(const ::testing::TestParamInfo<CorpusCase>& p) {
  return std::string(test::corpusMeshes()[std::get<0>(p.param)].name) + "_" + test::actionName(std::get<1>(p.param));
}

INSTANTIATE_TEST_SUITE_P(Meshes, OrganCorpus,
                         ::testing::Combine(::testing::Range<std::size_t>(0, test::corpusMeshes().size()),
                                            ::testing::Values(test::CorpusAction::Grasp,
                                                              test::CorpusAction::StraightCut,
                                                              test::CorpusAction::CurvedCut)),
                         caseName);

// The shared open meshes (SOURCES.md: "must be refused clearly") are refused at load under geometry.mesh, naming
// the mesh file and what is wrong.
TEST(OrganCorpusOpenMeshes, AreRefusedNamingTheKeyAndTheDefect) {
  for (const char* name : {"frog_body.obj", "c_open.obj"}) {
    const std::string path = test::sharedPath(std::string("organs/") + name);
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent (shared organ meshes are not committed)";
    const std::string scene = R"({"geometry": {"kind": "mesh", "mesh": ")" + path +
                              R"(", "mesh_scale": 0.01}, "models": {"pbd_metaballs": true}})";
    try {
      parseScene(scene, "user.json", ".");
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), "geometry.mesh") << e.what();
      EXPECT_NE(e.reason().find(name), std::string::npos) << e.what();
      EXPECT_NE(e.reason().find("closed, manifold, consistently oriented surface is needed"), std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace inc
