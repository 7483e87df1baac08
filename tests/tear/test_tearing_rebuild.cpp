// The device rebuild algorithms (per-particle fans and radix sorts, CPU references) equal the host adjacency + PBD
// model rebuild after many tearing steps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "cpu_fallback/tearing_cpu.h"
#include "host/tear/tearing_driver.h"
#include "host/tear/tearing_rebuild.h"
#include "model/input_error.h"
#include "model/tearing_sheet.h"
#include "physics/tearing_rebuild.h"

using namespace inc;

namespace {

// Torn sheet: jiggled steps of the CPU tearing step (thousands of splits), so edges of every kind (boundary,
// interior, doubled by a split) and split particles with moved rest positions are present.
template <typename T>
TearSheet<T> tornSheet(bool tube, int steps, std::uint32_t seed) {
  TearSheet<T> s = tube ? makeTearTube<T>(24, 20, 0.04, 0.2, 2.2, 1.0e4, 120.0)
                        : makeTearGrid<T>(30, 24, 0.01, 2.2, Vec3d(0, 0, 0), 1.0e4, 120.0);
  fixTearParticles(s, Vec3d(-1, -1, -1), Vec3d(1, 0.005, 0.005));
  TearParams<T> p;
  p.seed = seed;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < steps; ++k) {
    for (std::size_t i = 0; i < s.size(); ++i) s.x[i] = s.rest[i] + Vec3<T>(Vec3d(u(rng), u(rng), u(rng)) * 0.0012);
    cpu::tearStepCpu(s, p);
  }
  return s;
}

template <typename T>
void expectSameBlock(const PbdConstraintBlock<T>& a, const PbdConstraintBlock<T>& b, const char* what) {
  EXPECT_EQ(a.ids, b.ids) << what;
  EXPECT_EQ(a.offsets, b.offsets) << what;
  EXPECT_EQ(a.rest, b.rest) << what;  // the same expression on the same inputs: bit for bit
  EXPECT_EQ(a.compliance, b.compliance) << what;
  EXPECT_EQ(a.particle_offsets, b.particle_offsets) << what;
  EXPECT_EQ(a.particle_slots, b.particle_slots) << what;
  EXPECT_EQ(a.jacobi_scale, b.jacobi_scale) << what;
  EXPECT_EQ(a.stiffness, b.stiffness) << what;
}

template <typename T>
void expectSortedEqualsHost(const TearSheet<T>& torn) {
  TearSheet<T> s = torn;
  s.rebuildTopology();
  TearModelOptions opt;
  opt.stretch_compliance = 2e-4;
  opt.bending_compliance = 7.0;
  opt.pbd_stiffness = 0.9;
  opt.coloring = false;
  const PbdModel<T> m = buildTearPbdModel(s, opt);
  ASSERT_EQ(m.blocks.size(), 2u);
  for (const int algo : {0, 1, 2}) {  // per-particle fans (fan copies as on the device, none), radix sorts
    SCOPED_TRACE(algo == 0 ? "per-particle fans" : (algo == 1 ? "per-particle fans, uncached" : "radix sorts"));
    const TearSortedRebuild<T> r = algo == 0   ? rebuildTearFans(torn, opt)
                                   : algo == 1 ? rebuildTearFans(torn, opt, 0)
                                               : rebuildTearSorted(torn, opt);
    EXPECT_EQ(r.pt_offsets, s.pt_offsets);
    EXPECT_EQ(r.pt_tris, s.pt_tris);
    EXPECT_EQ(r.edge_a, s.edge_a);
    EXPECT_EQ(r.edge_b, s.edge_b);
    EXPECT_EQ(r.pe_offsets, s.pe_offsets);
    EXPECT_EQ(r.pe_partner, s.pe_partner);
    expectSameBlock(r.distance, m.blocks[0], "distance");
    expectSameBlock(r.bending, m.blocks[1], "bending");
  }
}

// A hand-made sheet: particle 0 at the centre of a fan of `spokes` triangles (far more than a lattice's six),
// an unused particle, a three-triangle "book" on one edge (non-manifold: a distance constraint, no bending)
// and fixed particles.
TearSheet<double> fanSheet(int spokes) {
  TearSheet<double> s;
  s.rest.push_back(Vec3d(0, 0, 0));
  for (int i = 0; i < spokes; ++i) {
    const double a = 6.283185307179586 * i / spokes;
    s.rest.push_back(Vec3d(0.01 * std::cos(a), 0.01 * std::sin(a), 0.001 * (i % 3)));
  }
  for (int i = 0; i < spokes; ++i) s.tris.push_back({0, 1 + i, 1 + (i + 1) % spokes});
  s.rest.push_back(Vec3d(1, 1, 1));  // unused: no triangle
  // Book: edge u-v with three leaves.
  const std::int32_t u = std::int32_t(s.rest.size());
  s.rest.push_back(Vec3d(0.1, 0, 0));
  s.rest.push_back(Vec3d(0.1, 0.01, 0));
  s.rest.push_back(Vec3d(0.11, 0.005, 0));
  s.rest.push_back(Vec3d(0.09, 0.005, 0.001));
  s.rest.push_back(Vec3d(0.1, 0.005, 0.01));
  s.tris.push_back({u, u + 1, u + 2});
  s.tris.push_back({u + 1, u, u + 3});
  s.tris.push_back({u, u + 1, u + 4});
  s.tris.push_back({u + 2, u + 1, 2});  // joins the book to the fan's rim
  const std::size_t n = s.rest.size();
  s.x = s.rest;
  s.v.assign(n, Vec3d());
  s.mass.assign(n, 1e-3);
  s.fixed.assign(n, 0);
  s.fixed[3] = s.fixed[std::size_t(u) + 4] = 1;
  s.k.assign(n, 1e4);
  s.tau_f.assign(n, 1e3);
  s.ref_normal.assign(s.tris.size(), Vec3d(0, 0, 1));
  return s;
}

}  // namespace

// The three sorts behind sortRowLocal (register network up to 16, per-thread copy up to 32, in place beyond) give
// std::sort's row for every length across their bounds, with repeated values and negative ones.
TEST(TearingRebuild, RowSortsOfEveryLengthEqualStdSort) {
  std::uint32_t state = 12345u;
  for (int n = 0; n <= 40; ++n) {
    for (int trial = 0; trial < 5; ++trial) {
      std::vector<std::int32_t> row(std::size_t(n) + 1, 0);
      for (int i = 0; i < n; ++i) {
        state = state * 1664525u + 1013904223u;
        row[std::size_t(i)] = std::int32_t(state >> 8) % 97 - 20;
      }
      row[std::size_t(n)] = 777;  // past the row: must stay untouched
      std::vector<std::int32_t> want(row.begin(), row.begin() + n);
      std::sort(want.begin(), want.end());
      tear::sortRowLocal(row.data(), n);
      ASSERT_EQ(std::vector<std::int32_t>(row.begin(), row.begin() + n), want) << "n " << n;
      ASSERT_EQ(row[std::size_t(n)], 777) << "n " << n;
    }
  }
}

TEST(TearingRebuild, RowSortAndFanCounts) {
  std::int32_t a[] = {9, 3, 7, 3, -1, 12, 0};
  tear::sortRow(a, 7);
  EXPECT_TRUE(std::is_sorted(a, a + 7));
  EXPECT_EQ(a[0], -1);
  EXPECT_EQ(a[6], 12);
  tear::sortRow(a, 0);  // empty rows are fine
  // A 40-spoke fan: the centre has 40 partners (all above it: 40 edges) and each spoke has two triangles (40
  // bending constraints at the centre).
  TearSheet<double> s = fanSheet(40);
  s.rebuildTopology();
  tear::Fan f;
  f.tris = s.tris.front().data();
  f.pt_offsets = s.pt_offsets.data();
  f.pt_tris = s.pt_tris.data();
  const tear::FanCounts c = tear::fanCounts(f, 0);
  EXPECT_EQ(c.partners, 40);
  EXPECT_EQ(c.upper, 40);
  EXPECT_EQ(c.bend_upper, 40);
  const tear::FanCounts unused = tear::fanCounts(f, 41);
  EXPECT_EQ(unused.partners + unused.upper + unused.bend_upper, 0);
  // The register path (fans of up to kFanPairs triangles) and the global reads count the same on a torn sheet.
  TearSheet<double> torn = tornSheet<double>(false, 8, 5);
  torn.rebuildTopology();
  f.tris = torn.tris.front().data();
  f.pt_offsets = torn.pt_offsets.data();
  f.pt_tris = torn.pt_tris.data();
  int cached = 0;
  for (std::size_t p = 0; p < torn.size(); ++p) {
    const tear::FanCounts a = tear::fanCounts(f, std::int32_t(p)), b = tear::fanCounts(f, std::int32_t(p), 0);
    ASSERT_EQ(a.partners, b.partners) << p;
    ASSERT_EQ(a.upper, b.upper) << p;
    ASSERT_EQ(a.bend_upper, b.bend_upper) << p;
    cached += torn.pt_offsets[p + 1] - torn.pt_offsets[p] <= tear::kFanPairs ? 1 : 0;
  }
  EXPECT_EQ(cached, int(torn.size())) << "a torn lattice's fans fit the register path";
}

// Fans far larger than a lattice's, an unused particle and a non-manifold edge: the per-particle rebuild has no
// local capacity to overflow and equals the host rebuild.
TEST(TearingRebuild, LargeFansAndNonManifoldEdgesEqualHostRebuild) {
  for (int spokes : {3, 7, 64, 300}) {
    SCOPED_TRACE(spokes);
    expectSortedEqualsHost(fanSheet(spokes));
  }
}

TEST(TearingRebuild, IndexBitsAndKeys) {
  EXPECT_EQ(tear::indexBits(0), 1);
  EXPECT_EQ(tear::indexBits(1), 1);
  EXPECT_EQ(tear::indexBits(2), 2);
  EXPECT_EQ(tear::indexBits(150000), 18);  // 2^17 = 131072 <= 150000 < 2^18
  EXPECT_EQ(tear::indexBits(262143), 18);
  EXPECT_EQ(tear::indexBits(262144), 19);
  const int bits = tear::indexBits(300000);
  const std::uint64_t k = tear::packEdge(299999, 17, bits);
  EXPECT_EQ(tear::edgeHigh(k, bits), 17);
  EXPECT_EQ(tear::edgeLow(k, bits), 299999);
  EXPECT_LT(tear::packEdge(3, 9, bits), tear::packEdge(4, 5, bits));  // (a, b) lexicographic
  const std::uint32_t keys[] = {0, 0, 2, 2, 2, 5};
  EXPECT_EQ(tear::lowerBound<std::uint32_t>(keys, 6, 1u), 2);
  EXPECT_EQ(tear::lowerBound<std::uint32_t>(keys, 6, 2u), 2);
  EXPECT_EQ(tear::lowerBound<std::uint32_t>(keys, 6, 6u), 6);
}

TEST(TearingRebuild, UntornGridAndTubeEqualHostRebuild) {
  expectSortedEqualsHost(tornSheet<double>(false, 0, 1));
  expectSortedEqualsHost(tornSheet<float>(true, 0, 1));
}

TEST(TearingRebuild, TornSheetsEqualHostRebuild) {
  const TearSheet<double> grid = tornSheet<double>(false, 8, 5);
  EXPECT_GT(grid.size(), 720u + 500u) << "the sheet must be well torn";
  expectSortedEqualsHost(grid);
  const TearSheet<float> tube = tornSheet<float>(true, 8, 9);
  EXPECT_GT(tube.size(), 480u + 300u);
  expectSortedEqualsHost(tube);
}

// The driver's host path reports its stages (the breakdown bench_tearing prints) and stays on the host on the CPU.
TEST(TearingRebuild, HostPathStagesAndCpuNeverResident) {
  TearSheet<double> s = makeTearGrid<double>(16, 8, 0.01, 2.2, Vec3d(0, 0, 0), 1.0e4, 150.0);
  fixTearParticles(s, Vec3d(-1, -1, -1), Vec3d(1e-3, 1, 1));
  PbdStepParams<double> sp;
  sp.gravity = Vec3d(0, 0, 0);
  sp.volume_preservation = false;
  TearModelOptions mo;
  mo.stretch_compliance = 2e-4;
  mo.bending_compliance = 10;
  TearingDriver<double> d(s, TearParams<double>(), mo, sp, BackendKind::Cpu);
  EXPECT_FALSE(d.deviceResident());
  EXPECT_THROW(d.setSummaryEvery(0), InputError);
  std::vector<std::int32_t> grasp;
  for (std::size_t i = 0; i < d.sheet().size(); ++i)
    if (d.sheet().rest[i].x > 0.149) grasp.push_back(std::int32_t(i));
  bool saw_rebuild = false;
  for (int f = 0; f < 12 && !saw_rebuild; ++f) {
    std::vector<Vec3d> to;
    for (std::int32_t id : grasp) to.push_back(d.sheet().rest[id] + Vec3d(0.01 * (f + 1), 0, 0));
    const TearFrameStats st = d.advance(grasp, to);
    EXPECT_FALSE(st.device_resident);
    std::vector<std::string> names;
    for (const StageTime& t : st.stages) {
      names.push_back(t.stage);
      EXPECT_GE(t.ms, 0.0) << t.stage;
    }
    auto has = [&](const char* n) { return std::find(names.begin(), names.end(), n) != names.end(); };
    EXPECT_TRUE(has("solve") && has("download_state") && has("tear_step"));
    EXPECT_EQ(has("host_model"), st.splits > 0) << "the model is rebuilt exactly on frames with splits";
    saw_rebuild = st.splits > 0;
    EXPECT_EQ(d.particleCount(), d.sheet().size());
  }
  EXPECT_TRUE(saw_rebuild) << "the pull must tear within 12 frames";
}
