// Tests for findNeighbors (host/backends/neighbor_search.h) on the CPU backend: cell-size choice, options, bad input.
#include <gtest/gtest.h>

#include <limits>

#include "cpu_fallback/neighbor_bruteforce.h"
#include "host/backends/neighbor_search.h"
#include "model/input_error.h"
#include "tests/support/neighbor_clouds.h"

using namespace inc;
using namespace inc::testing_neighbors;

namespace {

TEST(NeighborSearchDispatch, SelfAndCrossEqualBruteForceForEveryOption) {
  const auto pts = clusteredCloud<double>(1500, 21);
  const auto tool = randomCloud<double>(200, 22);
  std::vector<double> radii(tool.size());
  for (std::size_t i = 0; i < radii.size(); ++i) radii[i] = 0.02 * double(i % 6);  // includes radius 0
  for (double cell : {0.0, 0.013, 0.5})
    for (bool morton : {false, true}) {
      NeighborSearchOptions o;
      o.cell_size = cell;
      o.morton_order = morton;
      const std::string tag = "cell " + std::to_string(cell) + (morton ? " morton" : "");
      expectSameLists(findNeighbors(BackendKind::Cpu, pts, 0.04, o),
                      cpu::bruteForceNeighbors(pts, pts, std::vector<double>{0.04}, true), tag + " self");
      expectSameLists(findNeighbors(BackendKind::Cpu, tool, pts, radii, o),
                      cpu::bruteForceNeighbors(tool, pts, radii, false), tag + " cross");
    }
}

TEST(NeighborSearchDispatch, ZeroRadiusListsOnlyCoincidentPoints) {
  std::vector<Vec3f> pts = randomCloud<float>(100, 23);
  pts[50] = pts[3];
  const NeighborLists l = findNeighbors(BackendKind::Cpu, pts, 0.0f);  // cell size falls back to 1
  EXPECT_EQ(l.indices.size(), 2u);
  EXPECT_EQ(l.count(3), 1u);
  EXPECT_EQ(l.count(50), 1u);
}

TEST(NeighborSearchDispatch, BadInputThrowsInputError) {
  const auto pts = randomCloud<float>(50, 24);
  try {
    findNeighbors(BackendKind::Cpu, pts, std::numeric_limits<float>::quiet_NaN());
    FAIL() << "NaN radius accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "radius");
  }
  try {
    findNeighbors(BackendKind::Cpu, pts, pts, std::vector<float>(50, 0.1f), NeighborSearchOptions{});
    std::vector<float> radii(50, 0.1f);
    radii[9] = -0.5f;
    findNeighbors(BackendKind::Cpu, pts, pts, radii);
    FAIL() << "negative radius accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "radii[9]");
  }
  EXPECT_THROW(findNeighbors(BackendKind::Cpu, pts, pts, std::vector<float>(7, 0.1f)), InputError);
  auto bad = pts;
  bad[5].z = std::numeric_limits<float>::infinity();
  EXPECT_THROW(findNeighbors(BackendKind::Cpu, bad, 0.1f), InputError);
}

}  // namespace
