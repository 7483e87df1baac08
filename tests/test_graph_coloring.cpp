// Tests for the greedy constraint colouring: validity on lattices and random graphs, fixed particles, bad input.
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "host/graph_coloring.h"
#include "host/pbd_builders.h"

using namespace inc;

TEST(GraphColoring, ChainNeedsTwoColoursAndIsValid) {
  std::vector<std::int32_t> off{0}, ids;
  for (int i = 0; i < 9; ++i) {
    ids.push_back(i);
    ids.push_back(i + 1);
    off.push_back(std::int32_t(ids.size()));
  }
  const ConstraintColoring c = colorConstraints(off, ids, 10);
  EXPECT_EQ(c.colorCount(), 2);
  EXPECT_TRUE(coloringIsValid(c, off, ids, 10));
  // A deliberately broken colouring is caught.
  ConstraintColoring bad = c;
  bad.color.assign(9, 0);
  bad.color_offsets = {0, 9};
  for (int i = 0; i < 9; ++i) bad.order[i] = i;
  EXPECT_FALSE(coloringIsValid(bad, off, ids, 10));
}

TEST(GraphColoring, EveryBlockOfALatticeOrganIsValid) {
  const MetaballModel mb = makeLatticeMetaballs(Vec3d(0, 0, 0), Vec3d(0.05, 0.03, 0.03), 0.01, 0.75, 1000.0);
  MetaballPbdOptions opt;
  opt.volume_samples = 0;
  const PbdModel<double> m = buildMetaballPbdModel<double>(mb, opt);
  ASSERT_EQ(m.blocks.size(), 3u);
  for (const auto& b : m.blocks) {
    EXPECT_TRUE(coloringIsValid(b.coloring, b.offsets, b.ids, m.size())) << pbdConstraintKindName(b.kind);
    EXPECT_GE(b.coloring.colorCount(), 2);
    // Greedy bound: at most (max number of constraints sharing a particle with one constraint) + 1 colours.
    int max_conflicts = 0;
    for (std::size_t c = 0; c < b.count(); ++c) {
      int conflicts = 0;
      for (std::int32_t s = b.offsets[c]; s < b.offsets[c + 1]; ++s) {
        const std::int32_t p = b.ids[s];
        conflicts += b.particle_offsets[p + 1] - b.particle_offsets[p] - 1;
      }
      max_conflicts = std::max(max_conflicts, conflicts);
    }
    EXPECT_LE(b.coloring.colorCount(), max_conflicts + 1);
  }
}

TEST(GraphColoring, RandomHypergraphsAndFixedParticles) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 50 + trial * 10;
    std::uniform_int_distribution<int> pick(0, n - 1), size(2, 6);
    std::vector<std::int32_t> off{0}, ids;
    for (int c = 0; c < 3 * n; ++c) {
      const int k = size(rng);
      for (int q = 0; q < k; ++q) ids.push_back(pick(rng));
      off.push_back(std::int32_t(ids.size()));
    }
    std::vector<std::uint8_t> fixed(n, 0);
    for (int i = 0; i < n; i += 7) fixed[i] = 1;
    const ConstraintColoring a = colorConstraints(off, ids, n);
    const ConstraintColoring b = colorConstraints(off, ids, n, fixed);
    EXPECT_TRUE(coloringIsValid(a, off, ids, n));
    EXPECT_TRUE(coloringIsValid(b, off, ids, n, fixed));
  }
}

TEST(GraphColoring, RejectsOutOfRangeIndices) {
  std::vector<std::int32_t> off{0, 2}, ids{0, 5};
  EXPECT_THROW(colorConstraints(off, ids, 3), std::invalid_argument);
}
