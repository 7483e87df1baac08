// Tests for the greedy constraint colouring: validity on lattices and random graphs, fixed particles, bad input,
// models built without one (Jacobi only) and with reused cell volumes (what a cut's per-conversion rebuild skips).
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

#include "cpu_fallback/pbd_solver_cpu.h"
#include "host/assembly/pbd_builders.h"
#include "model/graph_coloring.h"
#include "model/input_error.h"

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

// A model built without colouring (MetaballPbdOptions::coloring = false, what a Jacobi dissection rebuilds per
// conversion) runs Jacobi exactly as the coloured model (Jacobi never reads the colouring: the same bits after 20
// frames, with volume preservation's parallel power-cell volumes equal too), and Gauss-Seidel on it is an
// InputError naming the solver, not a frame that silently skips every constraint.
TEST(GraphColoring, JacobiOnlyModelRunsJacobiAndRefusesGaussSeidel) {
  const MetaballModel mb = makeLatticeMetaballs(Vec3d(0, 0, 0), Vec3d(0.05, 0.03, 0.03), 0.01, 0.75, 1000.0);
  MetaballPbdOptions opt;
  opt.fixed.push_back({Vec3d(-1, -1, -1), Vec3d(0.005, 1, 1)});
  const PbdModel<double> coloured = buildMetaballPbdModel<double>(mb, opt);
  opt.coloring = false;
  const PbdModel<double> plain = buildMetaballPbdModel<double>(mb, opt);
  EXPECT_TRUE(pbdModelHasColoring(coloured));
  EXPECT_FALSE(pbdModelHasColoring(plain));
  ASSERT_EQ(plain.rest_cell_volume, coloured.rest_cell_volume);
  ASSERT_FALSE(plain.rest_cell_volume.empty());
  PbdStepParams<double> p;
  p.solver = PbdSolverKind::Jacobi;
  auto a = cpu::makePbdCpuBackend<double>();
  auto b = cpu::makePbdCpuBackend<double>();
  a->setModel(coloured);
  b->setModel(plain);
  for (int f = 0; f < 20; ++f) {
    a->advanceFrame(p, {});
    b->advanceFrame(p, {});
  }
  PbdState<double> sa, sb;
  a->getState(sa);
  b->getState(sb);
  double moved = 0;
  for (std::size_t i = 0; i < sa.positions.size(); ++i) {
    ASSERT_EQ(sa.positions[i].x, sb.positions[i].x) << i;
    ASSERT_EQ(sa.positions[i].y, sb.positions[i].y) << i;
    ASSERT_EQ(sa.positions[i].z, sb.positions[i].z) << i;
    moved = std::max(moved, norm(sa.positions[i] - coloured.rest_positions[i]));
  }
  EXPECT_GT(moved, 1e-5);  // the beam sagged: the comparison saw a real motion
  p.solver = PbdSolverKind::GaussSeidel;
  try {
    b->advanceFrame(p, {});
    FAIL() << "Gauss-Seidel ran on a model without colouring";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("solver"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(a->advanceFrame(p, {}));
}

// Rest cell volumes passed in MetaballPbdOptions::known_cell_volumes are taken as they are (NaN entries computed),
// and a sphere whose link set did not change gets the same bits as a fresh build: the reuse the dissection makes when
// a conversion removes spheres is exact. A wrong-sized list is an InputError naming the key.
TEST(GraphColoring, KnownCellVolumesOfUnchangedNeighbourhoodsAreExact) {
  const MetaballModel full = makeLatticeMetaballs(Vec3d(0, 0, 0), Vec3d(0.05, 0.03, 0.03), 0.01, 0.75, 1000.0);
  MetaballPbdOptions opt;
  opt.fixed.push_back({Vec3d(-1, -1, -1), Vec3d(0.005, 1, 1)});
  const PbdModel<float> base = buildMetaballPbdModel<float>(full, opt);
  // Remove sphere `gone` and its links, as a stroke rebuild does.
  const std::int32_t gone = std::int32_t(full.size() / 2);
  MetaballModel sub;
  std::vector<std::int32_t> to_sub(full.size(), -1), to_full;
  for (std::size_t i = 0; i < full.size(); ++i) {
    if (std::int32_t(i) == gone) continue;
    to_sub[i] = std::int32_t(sub.size());
    to_full.push_back(std::int32_t(i));
    sub.rest_centers.push_back(full.rest_centers[i]);
    sub.rest_radii.push_back(full.rest_radii[i]);
    sub.masses.push_back(full.masses[i]);
  }
  std::vector<char> lost(full.size(), 0);
  for (std::size_t l = 0; l < full.links.size(); ++l) {
    const auto& e = full.links[l];
    if (e[0] == gone || e[1] == gone) {
      lost[std::size_t(e[0])] = lost[std::size_t(e[1])] = 1;
      continue;
    }
    sub.links.push_back({to_sub[std::size_t(e[0])], to_sub[std::size_t(e[1])]});
    sub.link_rest_lengths.push_back(full.link_rest_lengths[l]);
  }
  const PbdModel<float> fresh = buildMetaballPbdModel<float>(sub, opt);
  MetaballPbdOptions reuse = opt;
  reuse.known_cell_volumes.assign(sub.size(), std::numeric_limits<double>::quiet_NaN());
  int reused = 0;
  for (std::size_t i = 0; i < sub.size(); ++i)
    if (!lost[std::size_t(to_full[i])]) {
      reuse.known_cell_volumes[i] = base.rest_cell_volume[std::size_t(to_full[i])];
      ++reused;
    }
  EXPECT_GT(reused, int(sub.size()) / 2);
  EXPECT_LT(reused, int(sub.size()));  // the lost neighbours' volumes are recomputed
  const PbdModel<float> built = buildMetaballPbdModel<float>(sub, reuse);
  ASSERT_EQ(built.rest_cell_volume, fresh.rest_cell_volume);
  bool some_changed = false;  // the recomputed ones differ from the base: the comparison can fail
  for (std::size_t i = 0; i < sub.size(); ++i)
    if (lost[std::size_t(to_full[i])])
      some_changed |= fresh.rest_cell_volume[i] != base.rest_cell_volume[std::size_t(to_full[i])];
  EXPECT_TRUE(some_changed);
  reuse.known_cell_volumes[0] = 1.25e-6;  // a given value is taken as it is
  EXPECT_EQ(buildMetaballPbdModel<float>(sub, reuse).rest_cell_volume[0], 1.25e-6f);
  reuse.known_cell_volumes.pop_back();
  try {
    buildMetaballPbdModel<float>(sub, reuse);
    FAIL() << "a wrong-sized known_cell_volumes was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("known_cell_volumes"), std::string::npos) << e.what();
  }
}
