// Tests for the CPU grid neighbour search: exact equality with the O(N^2) oracle, conventions and edge cases.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <limits>
#include <random>
#include <thread>

#include "cpu_fallback/neighbor_bruteforce.h"
#include "cpu_fallback/neighbor_search_cpu.h"
#include "model/input_error.h"
#include "tests/support/neighbor_clouds.h"

using namespace inc;
using namespace inc::testing_neighbors;

namespace {

template <typename T>
class NeighborSearchCpu : public ::testing::Test {};
using Precisions = ::testing::Types<float, double>;
TYPED_TEST_SUITE(NeighborSearchCpu, Precisions);

// Self-query of the grid (both storage orders, cell size = radius) against brute force: exact equality.
template <typename T>
void expectSelfMatchesBruteForce(const std::vector<Vec3<T>>& pts, const std::vector<T>& radii,
                                 const std::string& what) {
  for (T r : radii)
    for (bool morton : {false, true}) {
      cpu::GridNeighborSearch<T> s(pts, r, morton);
      const NeighborLists got = s.querySelf(r);
      const NeighborLists want = cpu::bruteForceNeighbors(pts, pts, std::vector<T>{r}, true);
      expectSameLists(got, want, what + " r=" + std::to_string(double(r)) + (morton ? " morton" : " bucket-order"));
      expectCanonical(got, true, what);
    }
}

TYPED_TEST(NeighborSearchCpu, RandomCloudEqualsBruteForce) {
  using T = TypeParam;
  // 3000 points in the unit cube: r = 0.134 gives ~30 neighbours; 0.2 about 100; 0.02 mostly empty lists
  expectSelfMatchesBruteForce(randomCloud<T>(3000, 1), {T(0.02), T(0.08), T(0.134), T(0.2)}, "random");
}

TYPED_TEST(NeighborSearchCpu, ClusteredCloudEqualsBruteForceWithHundredsOfNeighbours) {
  using T = TypeParam;
  const auto pts = clusteredCloud<T>(3000, 2);
  expectSelfMatchesBruteForce(pts, {T(0.01), T(0.05), T(0.12)}, "clustered");
  // the dense core really does exceed any "expected" neighbour count: lists are complete, not truncated
  const NeighborLists l = cpu::GridNeighborSearch<T>(pts, T(0.05)).querySelf(T(0.05));
  std::size_t most = 0;
  for (std::size_t q = 0; q < l.queryCount(); ++q) most = std::max(most, l.count(q));
  EXPECT_GT(most, 400u);
}

TYPED_TEST(NeighborSearchCpu, LatticeWithBoundaryTiesEqualsBruteForce) {
  using T = TypeParam;
  // spacing 0.125 is exact in binary: pairs at exactly r = 0.125, 0.25 must be kept (closed ball), and many
  // points sit exactly on cell boundaries when the cell size equals the radius
  const auto pts = latticeCloud<T>(14, 13, 12, T(0.125), 3);
  expectSelfMatchesBruteForce(pts, {T(0.125), T(0.17677669529663687), T(0.25), T(0.3)}, "lattice");
  const NeighborLists l = cpu::GridNeighborSearch<T>(pts, T(0.125)).querySelf(T(0.125));
  std::size_t six = 0;  // interior points of a cubic lattice have exactly 6 neighbours at distance h
  for (std::size_t q = 0; q < l.queryCount(); ++q) six += l.count(q) == 6;
  EXPECT_EQ(six, std::size_t(12 * 11 * 10));
}

TYPED_TEST(NeighborSearchCpu, CellSizeSmallerOrLargerThanRadius) {
  using T = TypeParam;
  const auto pts = randomCloud<T>(2000, 4);
  const T r = T(0.1);
  const NeighborLists want = cpu::bruteForceNeighbors(pts, pts, std::vector<T>{r}, true);
  for (T cell : {T(0.013), T(0.05), T(0.1), T(0.37), T(3.0)})
    for (bool morton : {false, true})
      expectSameLists(cpu::GridNeighborSearch<T>(pts, cell, morton).querySelf(r), want,
                      "cell " + std::to_string(double(cell)));
}

// Row trimming (neighborRowXRange) may only drop cells that hold no point within reach: random points near
// the reach of random queries, far from the origin (coordinates ~1e3, where float roundings of cell boundaries
// are largest relative to the cell), at cell sizes of r/3 to r. Every point within r of the query must have its
// row kept and its x cell inside the trimmed range; and with cells of r/2 the far corner rows are dropped.
TYPED_TEST(NeighborSearchCpu, RowTrimmingNeverDropsAPointWithinReach) {
  using T = TypeParam;
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::size_t tested = 0, trimmed_rows = 0;
  for (double factor : {1.0 / 3.0, 0.5, 0.77, 1.0}) {
    const T r = T(0.0371), h = T(double(r) * factor);
    const Vec3<T> lo(T(1000.0), T(-1000.5), T(0.25)), hi(T(1001.0), T(-999.5), T(1.25));
    const NeighborGridParams<T> p = makeNeighborGridParams(lo, hi, h, neighborBucketCount(1 << 20), 1, true);
    const T reach = neighborSearchReach(r);
    for (int q = 0; q < 4000; ++q) {
      const Vec3<T> x(T(1000.5 + 0.4 * u(rng)), T(-1000.0 + 0.4 * u(rng)), T(0.75 + 0.4 * u(rng)));
      const std::int32_t qc[3] = {neighborCellCoord(x.x, p.origin.x, p.inv_cell_x),
                                  neighborCellCoord(x.y, p.origin.y, p.inv_cell),
                                  neighborCellCoord(x.z, p.origin.z, p.inv_cell)};
      // a point at distance in [0.9 r, r] (plus exact ties along a diagonal) in a random direction
      Vec3<double> d(u(rng), u(rng), u(rng));
      const double len = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
      if (len < 1e-3) continue;
      const double s = double(r) * (0.9 + 0.1 * (u(rng) * 0.5 + 0.5)) / len;
      const Vec3<T> y(T(double(x.x) + d.x * s), T(double(x.y) + d.y * s), T(double(x.z) + d.z * s));
      if (distance2Exact(x, y) > r * r) continue;
      const std::int32_t cy = neighborCellCoord(y.y, p.origin.y, p.inv_cell);
      const std::int32_t cz = neighborCellCoord(y.z, p.origin.z, p.inv_cell);
      std::int32_t xl = neighborCellCoord(x.x - reach, p.origin.x, p.inv_cell_x);
      std::int32_t xh = neighborCellCoord(x.x + reach, p.origin.x, p.inv_cell_x);
      ASSERT_TRUE(neighborRowXRange(p, x, reach, qc, cy, cz, xl, xh)) << "factor " << factor << " query " << q;
      const std::int32_t cx = neighborCellCoord(y.x, p.origin.x, p.inv_cell_x);
      ASSERT_LE(xl, cx) << "factor " << factor << " query " << q;
      ASSERT_GE(xh, cx) << "factor " << factor << " query " << q;
      ++tested;
    }
    if (factor == 0.5) {  // a query at a cell centre: the (+-2, +-2) rows are at least 1.5 cells = 0.75 r away
      // in both y and z, i.e. 1.06 r: dropped.
      const Vec3<T> c = p.origin + Vec3<T>(T(10.5), T(10.5), T(10.5)) * h;
      const std::int32_t qc[3] = {10, 10, 10};
      for (int dy : {-2, 2})
        for (int dz : {-2, 2}) {
          std::int32_t xl = 8, xh = 12;
          trimmed_rows += !neighborRowXRange(p, c, reach, qc, 10 + dy, 10 + dz, xl, xh);
        }
    }
  }
  EXPECT_GT(tested, 10000u);
  EXPECT_EQ(trimmed_rows, 4u);
}

TYPED_TEST(NeighborSearchCpu, PerQueryRadiiLargerThanTheCellSize) {
  using T = TypeParam;
  const auto pts = clusteredCloud<T>(2500, 5);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(0.0, 0.25);
  std::vector<T> radii(pts.size());
  for (auto& r : radii) r = T(u(rng));  // up to 8x the cell size below
  for (bool morton : {false, true}) {
    cpu::GridNeighborSearch<T> s(pts, T(0.03), morton);
    expectSameLists(s.querySelf(radii), cpu::bruteForceNeighbors(pts, pts, radii, true), "per-point radii");
  }
}

TYPED_TEST(NeighborSearchCpu, QuerySetAgainstPointSet) {
  using T = TypeParam;
  const auto tissue = clusteredCloud<T>(3000, 7);
  // tool samples: some inside the tissue's box, some well outside it (negative cell coordinates)
  auto tool = randomCloud<T>(400, 8);
  for (std::size_t i = 0; i < tool.size(); i += 3) tool[i] = tool[i] * T(3) - Vec3<T>(T(1), T(1), T(1));
  std::vector<T> radii(tool.size());
  for (std::size_t i = 0; i < tool.size(); ++i) radii[i] = T(0.01) + T(0.3) * T(i % 7) / T(7);
  for (bool morton : {false, true}) {
    cpu::GridNeighborSearch<T> s(tissue, T(0.06), morton);
    expectSameLists(s.query(tool, T(0.06)), cpu::bruteForceNeighbors(tool, tissue, std::vector<T>{T(0.06)}, false),
                    "tool vs tissue, one radius");
    const NeighborLists got = s.query(tool, radii);
    expectSameLists(got, cpu::bruteForceNeighbors(tool, tissue, radii, false), "tool vs tissue, per-query radii");
    expectCanonical(got, false, "tool vs tissue");
  }
}

TYPED_TEST(NeighborSearchCpu, EmptyAndSinglePointSets) {
  using T = TypeParam;
  cpu::GridNeighborSearch<T> empty(std::vector<Vec3<T>>{}, T(1));
  EXPECT_EQ(empty.querySelf(T(1)).offsets, std::vector<std::int64_t>{0});
  const NeighborLists e = empty.query({Vec3<T>(), Vec3<T>(T(1), T(2), T(3))}, T(5));
  EXPECT_EQ(e.offsets, (std::vector<std::int64_t>{0, 0, 0}));
  EXPECT_TRUE(e.indices.empty());

  cpu::GridNeighborSearch<T> one(std::vector<Vec3<T>>{Vec3<T>(T(2), T(2), T(2))}, T(1));
  const NeighborLists s = one.querySelf(T(1));
  EXPECT_EQ(s.offsets, (std::vector<std::int64_t>{0, 0}));
  const NeighborLists q = one.query({Vec3<T>(T(2), T(2), T(3)), Vec3<T>(T(2), T(2), T(3.5))}, T(1));
  EXPECT_EQ(q.offsets, (std::vector<std::int64_t>{0, 1, 1}));  // distance exactly 1 is in, 1.5 is out
  EXPECT_EQ(q.indices, std::vector<std::int32_t>{0});
  EXPECT_TRUE(cpu::GridNeighborSearch<T>(std::vector<Vec3<T>>{}, T(1)).query({}, T(1)).indices.empty());
}

TYPED_TEST(NeighborSearchCpu, DistanceExactlyRadiusIsIncluded) {
  using T = TypeParam;
  // integer coordinates: squared distances 1, 2, 3 are exact in both precisions
  const std::vector<Vec3<T>> pts = {Vec3<T>(T(0), T(0), T(0)), Vec3<T>(T(1), T(0), T(0)), Vec3<T>(T(0), T(-1), T(0)),
                                    Vec3<T>(T(1), T(1), T(0)), Vec3<T>(T(1), T(1), T(1)), Vec3<T>(T(0), T(0), T(2))};
  for (T cell : {T(1), T(0.5), T(2)}) {
    cpu::GridNeighborSearch<T> s(pts, cell);
    const NeighborLists at = s.query({pts[0]}, T(1));
    EXPECT_EQ(at.indices, (std::vector<std::int32_t>{0, 1, 2}));
    const NeighborLists below = s.query({pts[0]}, std::nextafter(T(1), T(0)));
    EXPECT_EQ(below.indices, (std::vector<std::int32_t>{0}));
    const NeighborLists two = s.querySelf(T(2));  // distance exactly 2 (point 5) is in as well
    EXPECT_EQ(std::vector<std::int32_t>(two.indices.begin(), two.indices.begin() + two.offsets[1]),
              (std::vector<std::int32_t>{1, 2, 3, 4, 5}));
  }
}

TYPED_TEST(NeighborSearchCpu, AllPointsInOneCellListEveryOtherPoint) {
  using T = TypeParam;
  const std::size_t n = 600;
  auto pts = randomCloud<T>(n, 9);
  for (auto& x : pts) x = x * T(1e-3);
  for (bool morton : {false, true}) {
    const NeighborLists l = cpu::GridNeighborSearch<T>(pts, T(1), morton).querySelf(T(1));
    ASSERT_EQ(l.offsets.back(), std::int64_t(n * (n - 1)));
    for (std::size_t q = 0; q < n; ++q) {
      ASSERT_EQ(l.count(q), n - 1);
      std::int32_t expect = 0;
      for (std::int64_t e = l.offsets[q]; e < l.offsets[q + 1]; ++e, ++expect) {
        if (std::size_t(expect) == q) ++expect;
        ASSERT_EQ(l.indices[std::size_t(e)], expect);
      }
    }
  }
}

TYPED_TEST(NeighborSearchCpu, DuplicatePositionsAndZeroRadius) {
  using T = TypeParam;
  auto pts = randomCloud<T>(300, 10);
  for (std::size_t i = 0; i < 40; ++i) pts[100 + i] = pts[7];  // 41 copies of point 7
  for (T r : {T(0), T(0.05)}) {
    cpu::GridNeighborSearch<T> s(pts, r > 0 ? r : T(0.1));
    expectSameLists(s.querySelf(r), cpu::bruteForceNeighbors(pts, pts, std::vector<T>{r}, true), "duplicates");
  }
  const NeighborLists zero = cpu::GridNeighborSearch<T>(pts, T(0.1)).querySelf(T(0));
  EXPECT_EQ(zero.count(7), 40u);  // the copies, and nothing else (random points do not coincide)
  EXPECT_EQ(zero.count(0), 0u);
}

TYPED_TEST(NeighborSearchCpu, SparseHugeBoxIsHashedAndExact) {
  using T = TypeParam;
  const auto pts = sparseCloud<T>(700, 11);
  cpu::GridNeighborSearch<T> s(pts, T(1));
  EXPECT_TRUE(s.hashed()) << "a 2e6-wide box at cell size 1 must not get a dense grid";
  for (int a = 0; a < 3; ++a) EXPECT_LE(s.params().dims[a], kNeighborGridMaxCells);
  const NeighborLists got = s.querySelf(T(1));
  expectSameLists(got, cpu::bruteForceNeighbors(pts, pts, std::vector<T>{T(1)}, true), "sparse");
  EXPECT_GT(got.indices.size(), 500u);  // the groups do find each other
  cpu::GridNeighborSearch<T> m(pts, T(1), true);
  expectSameLists(m.querySelf(T(1)), got, "sparse, morton");
}

TYPED_TEST(NeighborSearchCpu, CellsSharingABucketDoNotListAPointTwice) {
  using T = TypeParam;
  const CollidingCloud<T> cc = collidingCloud<T>();
  for (bool morton : {false, true}) {
    cpu::GridNeighborSearch<T> s(cc.points, cc.cell, morton);
    ASSERT_TRUE(s.hashed());
    ASSERT_EQ(neighborBucket(s.params(), cc.c1[0], cc.c1[1], cc.c1[2]),
              neighborBucket(s.params(), cc.c2[0], cc.c2[1], cc.c2[2]));
    const NeighborLists l = s.querySelf(cc.radius);
    expectSameLists(l, cpu::bruteForceNeighbors(cc.points, cc.points, std::vector<T>{cc.radius}, true), "colliding");
    EXPECT_EQ(std::vector<std::int32_t>(l.indices.begin() + l.offsets[2], l.indices.begin() + l.offsets[3]),
              (std::vector<std::int32_t>{3, 4, 5}));
    // and with a radius larger than the cell (125 cells, more collisions)
    expectSameLists(s.querySelf(T(2.5)), cpu::bruteForceNeighbors(cc.points, cc.points, std::vector<T>{T(2.5)}, true),
                    "colliding, large radius");
  }
}

TYPED_TEST(NeighborSearchCpu, NonFiniteInputNamesTheEntry) {
  using T = TypeParam;
  auto pts = randomCloud<T>(50, 12);
  pts[17].y = std::numeric_limits<T>::quiet_NaN();
  try {
    cpu::GridNeighborSearch<T> s(pts, T(0.1));
    FAIL() << "NaN point accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "points[17]");
  }
  pts[17].y = T(0.5);
  pts[3].z = -std::numeric_limits<T>::infinity();
  EXPECT_THROW(cpu::GridNeighborSearch<T>(pts, T(0.1)), InputError);
  pts[3].z = T(0.5);
  cpu::GridNeighborSearch<T> s(pts, T(0.1));
  std::vector<Vec3<T>> q(4);
  q[2].x = std::numeric_limits<T>::infinity();
  try {
    s.query(q, T(0.1));
    FAIL() << "infinite query accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "queries[2]");
  }
  std::vector<T> radii(pts.size(), T(0.1));
  radii[31] = T(-1);
  try {
    s.querySelf(radii);
    FAIL() << "negative radius accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "radii[31]");
  }
  EXPECT_THROW(s.querySelf(std::numeric_limits<T>::quiet_NaN()), InputError);
  EXPECT_THROW(s.querySelf(std::numeric_limits<T>::infinity()), InputError);
  EXPECT_THROW(s.querySelf(std::vector<T>(3, T(0.1))), InputError);  // neither 1 nor n radii
  EXPECT_THROW(cpu::GridNeighborSearch<T>(pts, T(0)), InputError);
  EXPECT_THROW(cpu::GridNeighborSearch<T>(pts, -T(1)), InputError);
  EXPECT_THROW(cpu::GridNeighborSearch<T>(pts, std::numeric_limits<T>::denorm_min()), InputError);  // 1/h = inf
}

TYPED_TEST(NeighborSearchCpu, MortonOrderAndPermutations) {
  using T = TypeParam;
  const auto pts = randomCloud<T>(4000, 13);
  cpu::GridNeighborSearch<T> s(pts, T(0.05), true);
  const auto& perm = s.sortedToOriginal();
  const auto& inv = s.originalToSorted();
  ASSERT_EQ(perm.size(), pts.size());
  std::vector<int> seen(pts.size(), 0);
  std::uint32_t prev = 0;
  for (std::size_t slot = 0; slot < perm.size(); ++slot) {
    ASSERT_EQ(inv[std::size_t(perm[slot])], std::int32_t(slot));
    ++seen[std::size_t(perm[slot])];
    const Vec3<T>& x = s.sortedPoints()[slot];
    EXPECT_EQ(x.x, pts[std::size_t(perm[slot])].x);
    const auto& p = s.params();
    const std::uint32_t key = neighborMortonKey(p, neighborCellCoord(x.x, p.origin.x, p.inv_cell_x),
                                                neighborCellCoord(x.y, p.origin.y, p.inv_cell),
                                                neighborCellCoord(x.z, p.origin.z, p.inv_cell));
    ASSERT_GE(key, prev) << "storage order is not Z order at slot " << slot;
    prev = key;
  }
  for (int c : seen) ASSERT_EQ(c, 1);
}

// Storage-order lists name the same pairs as the original-order ones (mapped back through the permutation:
// exact equality with brute force), each row ascending in storage slots and without the query itself, for
// bucket and Morton order, dense and hashed grids, short and long rows.
TYPED_TEST(NeighborSearchCpu, StorageOrderListsAreThePermutedLists) {
  using T = TypeParam;
  const std::vector<NeighborCase<T>> cases = {
      {randomCloud<T>(3000, 21), T(0.06), T(0.03), "random"},
      {clusteredCloud<T>(3000, 22), T(0.04), T(0.04), "clustered"},
      {latticeCloud<T>(12, 10, 8, T(0.125), 23), T(0.125), T(0.125), "lattice ties"},
      {sparseCloud<T>(700, 24), T(1), T(1), "sparse hashed"},
      {oneCellCloud<T>(600, 9), T(1), T(1), "one cell"}};  // rows of 599
  for (const NeighborCase<T>& c : cases)
    for (bool morton : {false, true}) {
      const std::string tag = std::string(c.what) + (morton ? " morton" : " bucket-order");
      cpu::GridNeighborSearch<T> s(c.pts, c.cell, morton);
      const NeighborLists storage = s.querySelfStorage(c.r);
      expectCanonical(storage, true, tag + " storage");
      expectSameLists(storageListsToOriginal(storage, s.sortedToOriginal()),
                      cpu::bruteForceNeighbors(c.pts, c.pts, std::vector<T>{c.r}, true), tag + " vs brute force");
    }
  EXPECT_THROW(cpu::GridNeighborSearch<T>(cases[0].pts, T(0.1)).querySelfStorage(std::numeric_limits<T>::quiet_NaN()),
               InputError);
  EXPECT_TRUE(cpu::GridNeighborSearch<T>(std::vector<Vec3<T>>{}, T(1)).querySelfStorage(T(1)).indices.empty());
}

// The AVX2 scan (used where the CPU has it) and the portable one (SSE2 on x86-64, plain C++ elsewhere) give
// the same lists, equal to brute force: ties at the radius, rows of hundreds, clouds whose last rows end at
// the last slot (the vector scans read past it, masked), both list orders, self and tool queries.
TYPED_TEST(NeighborSearchCpu, PortableAndAvx2ScansGiveTheSameLists) {
  using T = TypeParam;
  const std::vector<NeighborCase<T>> cases = {
      {randomCloud<T>(2000, 34), T(0.1), T(0.05), "random"},
      {clusteredCloud<T>(2000, 35), T(0.04), T(0.02), "clustered"},
      {latticeCloud<T>(11, 9, 7, T(0.125), 36), T(0.25), T(0.125), "lattice ties"},
      {oneCellCloud<T>(300, 33), T(1), T(0.5), "one cell"}};
  auto tool = randomCloud<T>(200, 37);
  for (std::size_t i = 0; i < tool.size(); i += 4) tool[i] = tool[i] * T(2) - Vec3<T>(T(0.5), T(0.5), T(0.5));
  for (const NeighborCase<T>& c : cases)
    for (bool morton : {false, true}) {
      const std::string tag = std::string(c.what) + (morton ? " morton" : " bucket-order");
      const cpu::GridNeighborSearch<T> s(c.pts, c.cell, morton);
      const NeighborLists want = cpu::bruteForceNeighbors(c.pts, c.pts, std::vector<T>{c.r}, true);
      const NeighborLists want_tool = cpu::bruteForceNeighbors(tool, c.pts, std::vector<T>{c.r}, false);
      NeighborLists self[2], storage[2], tools[2];
      for (int portable : {1, 0}) {
        cpu::setNeighborScanPortable(portable == 1);
        self[portable] = s.querySelf(c.r);
        storage[portable] = s.querySelfStorage(c.r);
        tools[portable] = s.query(tool, c.r);
      }
      cpu::setNeighborScanPortable(false);
      expectSameLists(self[1], want, tag + " portable");
      expectSameLists(self[0], want, tag + " default scan");
      expectSameLists(storage[0], storage[1], tag + " storage order: default vs portable");
      expectSameLists(storageListsToOriginal(storage[1], s.sortedToOriginal()), want, tag + " storage order");
      expectSameLists(tools[1], want_tool, tag + " tool portable");
      expectSameLists(tools[0], want_tool, tag + " tool default scan");
    }
  if (!cpu::neighborScanUsesAvx2()) std::printf("note: no AVX2 on this CPU; both runs used the portable scan\n");
}

// Lists written into a reused NeighborLists, whose arrays are larger or smaller than the new lists, equal
// fresh ones (nothing stale is left behind, nothing is lost when the arrays grow).
TYPED_TEST(NeighborSearchCpu, ReusedOutputListsEqualFreshOnes) {
  using T = TypeParam;
  const auto pts = clusteredCloud<T>(3000, 38);
  const auto tool = randomCloud<T>(300, 39);
  cpu::GridNeighborSearch<T> s(pts, T(0.04));
  NeighborLists out;
  for (T r : {T(0.04), T(0.12), T(0.01), T(0.07)}) {
    const std::string tag = "r=" + std::to_string(double(r));
    s.querySelf(r, out);
    expectSameLists(out, cpu::bruteForceNeighbors(pts, pts, std::vector<T>{r}, true), tag + " self");
    s.querySelfStorage(r, out);
    expectSameLists(out, s.querySelfStorage(r), tag + " storage order");
    s.query(tool, r, out);
    expectSameLists(out, cpu::bruteForceNeighbors(tool, pts, std::vector<T>{r}, false), tag + " tool");
  }
  const auto fewer = randomCloud<T>(500, 40);
  s.build(fewer, T(0.1), true);
  s.querySelf(T(0.1), out);
  expectSameLists(out, cpu::bruteForceNeighbors(fewer, fewer, std::vector<T>{T(0.1)}, true), "rebuilt, fewer points");
}

// Const queries on one object from several threads at once (one caller takes the row buffers the object
// keeps, the others use their own) give the same lists as a single caller.
TYPED_TEST(NeighborSearchCpu, ConcurrentQueriesOnOneObject) {
  using T = TypeParam;
  const auto pts = clusteredCloud<T>(3000, 41);
  const cpu::GridNeighborSearch<T> s(pts, T(0.05), true);
  const NeighborLists want = s.querySelf(T(0.05));
  const NeighborLists want_storage = s.querySelfStorage(T(0.05));
  std::vector<NeighborLists> got(4);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < got.size(); ++t)
    threads.emplace_back([&s, &got, t] {
      for (int k = 0; k < 4; ++k) {
        if (t % 2) {
          s.querySelfStorage(T(0.05), got[t]);
        } else {
          s.querySelf(T(0.05), got[t]);
        }
      }
    });
  for (std::thread& th : threads) th.join();
  for (std::size_t t = 0; t < got.size(); ++t)
    expectSameLists(got[t], t % 2 ? want_storage : want, "thread " + std::to_string(t));
}

TYPED_TEST(NeighborSearchCpu, ResultDoesNotDependOnThreadCount) {
  using T = TypeParam;
  const auto pts = clusteredCloud<T>(3000, 14);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const NeighborLists one = cpu::GridNeighborSearch<T>(pts, T(0.05), true).querySelf(T(0.05));
  omp_set_num_threads(3);
  const NeighborLists three = cpu::GridNeighborSearch<T>(pts, T(0.05), true).querySelf(T(0.05));
  omp_set_num_threads(threads);
  expectSameLists(three, one, "1 vs 3 threads");
}

TYPED_TEST(NeighborSearchCpu, RebuildReusesTheObject) {
  using T = TypeParam;
  cpu::GridNeighborSearch<T> s;
  const auto a = randomCloud<T>(1000, 15), b = clusteredCloud<T>(1500, 16);
  s.build(a, T(0.1));
  expectSameLists(s.querySelf(T(0.1)), cpu::bruteForceNeighbors(a, a, std::vector<T>{T(0.1)}, true), "first build");
  s.build(b, T(0.04), true);
  EXPECT_EQ(s.size(), b.size());
  expectSameLists(s.querySelf(T(0.04)), cpu::bruteForceNeighbors(b, b, std::vector<T>{T(0.04)}, true), "rebuild");
}

}  // namespace
