// The bring-your-own-organ corpus on the CPU, or CUDA (issue 31): every corpus mesh, with the scene a user would write
// and every other key at its default, is grasped, cut straight and cut along a curve through `incision run`'s runner;
// the run must end and keep a closed, right-side-out surface of nearly its rest volume. Its own binary and ctest
// label `corpus` (not in CI yet: it takes tens of minutes on two cores and does not pass;
// docs/bring-your-own-organ.md).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <tuple>

#include "tests/support/organ_corpus.h"
#include "tests/support/repo_paths.h"

namespace inc {
namespace {

// The surface volume may drift this far from the rest volume (issue 31: "within a few per cent").
constexpr double kVolumeTolerance = 0.05;

using CorpusCase = std::tuple<std::size_t, test::CorpusAction>;

// The CPU fallback, or CUDA when INCISION_CORPUS_BACKEND=cuda (tools/gpu-check runs the corpus so).
BackendKind corpusBackend() {
  const char* b = std::getenv("INCISION_CORPUS_BACKEND");
  return b && std::string(b) == "cuda" ? BackendKind::Cuda : BackendKind::Cpu;
}

class OrganCorpus : public ::testing::TestWithParam<CorpusCase> {};

TEST_P(OrganCorpus, RunsToTheEndWithAClosedSurfaceOfItsVolume) {
  const test::CorpusMesh& cm = test::corpusMeshes()[std::get<0>(GetParam())];
  const test::CorpusAction action = std::get<1>(GetParam());
  const test::CorpusResult r = test::runCorpusCase(cm, action, corpusBackend());
  if (r.skipped) GTEST_SKIP() << r.skip_reason;
  const std::vector<std::string> failures = test::corpusFailures(r, action, kVolumeTolerance);
  const std::string verdict = failures.empty() ? "ok" : test::joinedFailures(failures);
  std::printf("[ corpus ] %s\n", test::corpusRow(cm, action, r, verdict).c_str());
  EXPECT_TRUE(failures.empty()) << cm.name << " " << test::actionName(action) << ": " << verdict;
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

}  // namespace
}  // namespace inc
