// GPU grid neighbour search: exact equality with brute force and with the CPU search, every edge case.
#include <gtest/gtest.h>

#if INCISION_HAVE_CUDA

#include <cmath>
#include <limits>
#include <random>

#include "cpu_fallback/neighbor_bruteforce.h"
#include "cpu_fallback/neighbor_search_cpu.h"
#include "host/backends/neighbor_search.h"
#include "kernels/device_buffer.h"
#include "kernels/device_info.h"
#include "kernels/neighbor_search_cuda.h"
#include "model/input_error.h"
#include "tests/support/neighbor_clouds.h"

using namespace inc;
using namespace inc::testing_neighbors;

namespace {

#define SKIP_WITHOUT_GPU()                                                        \
  do {                                                                            \
    if (cuda::queryDevices().device_count == 0) GTEST_SKIP() << "no CUDA device"; \
  } while (0)

template <typename T>
class NeighborSearchGpu : public ::testing::Test {};
using Precisions = ::testing::Types<float, double>;
TYPED_TEST_SUITE(NeighborSearchGpu, Precisions);

template <typename T>
std::vector<T> downloadArray(const T* d, std::size_t n) {
  std::vector<T> h(n);
  if (n) INC_CUDA(cudaMemcpy(h.data(), d, n * sizeof(T), cudaMemcpyDeviceToHost));
  return h;
}

template <typename T>
NeighborLists gpuSelf(const std::vector<Vec3<T>>& pts, T cell, T r, bool morton, bool two_pass = false) {
  cuda::GridNeighborSearch<T> s;
  if (two_pass) s.setStagingLimitBytes(0);  // count, then traverse again (no staged rows)
  s.build(pts, cell, morton);
  return s.querySelf(r).download();
}

// GPU self-query == brute force == CPU self-query, both storage orders, cell size = radius.
template <typename T>
void expectGpuSelfExact(const std::vector<Vec3<T>>& pts, const std::vector<T>& radii, const std::string& what) {
  for (T r : radii) {
    const NeighborLists want = cpu::bruteForceNeighbors(pts, pts, std::vector<T>{r}, true);
    for (bool morton : {false, true}) {
      const std::string tag = what + " r=" + std::to_string(double(r)) + (morton ? " morton" : " bucket-order");
      const NeighborLists got = gpuSelf(pts, r, r, morton);
      expectSameLists(got, want, tag + " vs brute force");
      expectSameLists(got, cpu::GridNeighborSearch<T>(pts, r, morton).querySelf(r), tag + " vs cpu");
      expectCanonical(got, true, tag);
      // the two-pass query (used when the staging scratch would exceed its limit) gives the same lists
      expectSameLists(gpuSelf(pts, r, r, morton, true), want, tag + " two-pass vs brute force");
    }
  }
}

TYPED_TEST(NeighborSearchGpu, RandomCloudEqualsBruteForceAndCpu) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  expectGpuSelfExact(randomCloud<T>(3000, 1), {T(0.02), T(0.08), T(0.134), T(0.2)}, "random");
}

TYPED_TEST(NeighborSearchGpu, ClusteredCloudWithHundredsOfNeighbours) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const auto pts = clusteredCloud<T>(3000, 2);
  expectGpuSelfExact(pts, {T(0.01), T(0.05), T(0.12)}, "clustered");
  const NeighborLists l = gpuSelf(pts, T(0.05), T(0.05), false);
  std::size_t most = 0;
  for (std::size_t q = 0; q < l.queryCount(); ++q) most = std::max(most, l.count(q));
  EXPECT_GT(most, 400u);  // far beyond any fixed per-particle capacity: lists are complete
}

TYPED_TEST(NeighborSearchGpu, LatticeWithBoundaryTies) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const auto pts = latticeCloud<T>(14, 13, 12, T(0.125), 3);
  expectGpuSelfExact(pts, {T(0.125), T(0.17677669529663687), T(0.25), T(0.3)}, "lattice");
  const NeighborLists l = gpuSelf(pts, T(0.125), T(0.125), true);
  std::size_t six = 0;
  for (std::size_t q = 0; q < l.queryCount(); ++q) six += l.count(q) == 6;
  EXPECT_EQ(six, std::size_t(12 * 11 * 10));
}

TYPED_TEST(NeighborSearchGpu, CellSizeSmallerOrLargerThanRadius) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const auto pts = randomCloud<T>(2000, 4);
  const T r = T(0.1);
  const NeighborLists want = cpu::bruteForceNeighbors(pts, pts, std::vector<T>{r}, true);
  for (T cell : {T(0.013), T(0.05), T(0.1), T(0.37), T(3.0)})
    for (bool morton : {false, true})
      expectSameLists(gpuSelf(pts, cell, r, morton), want, "cell " + std::to_string(double(cell)));
}

TYPED_TEST(NeighborSearchGpu, PerPointDeviceRadii) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const auto pts = clusteredCloud<T>(2500, 5);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(0.0, 0.25);
  std::vector<T> radii(pts.size());
  for (auto& r : radii) r = T(u(rng));
  cuda::DeviceBuffer<T> d_radii;
  d_radii.upload(radii);
  const NeighborLists want = cpu::bruteForceNeighbors(pts, pts, radii, true);
  for (bool morton : {false, true}) {
    cuda::GridNeighborSearch<T> s;
    s.build(pts, T(0.03), morton);
    cuda::DeviceNeighborLists out;
    s.querySelf(d_radii.data(), radii.size(), out);
    expectSameLists(out.download(), want, "per-point radii");
    expectSameLists(out.download(), cpu::GridNeighborSearch<T>(pts, T(0.03), morton).querySelf(radii), "vs cpu");
    // one radius given on the device (count 1): every query reads it
    cuda::DeviceBuffer<T> d_one;
    d_one.upload(std::vector<T>{T(0.07)});
    s.querySelf(d_one.data(), 1, out);
    expectSameLists(out.download(), s.querySelf(T(0.07)).download(), "one device radius");
  }
}

TYPED_TEST(NeighborSearchGpu, LargeSparseHashedCloudEqualsCpu) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const auto pts = sparseCloud<T>(30000, 20);  // ~60k points, hashed into 2^17 buckets: many sort blocks
  for (bool morton : {false, true}) {
    cuda::GridNeighborSearch<T> s;
    s.build(pts, T(1), morton);
    ASSERT_TRUE(s.hashed());
    const cpu::GridNeighborSearch<T> c(pts, T(1), morton);
    EXPECT_EQ(downloadArray(s.sortedToOriginal(), pts.size()), c.sortedToOriginal());
    expectSameLists(s.querySelf(T(1)).download(), c.querySelf(T(1)), "large sparse");
    expectSameLists(s.querySelf(T(3)).download(), c.querySelf(T(3)), "large sparse, radius 3 cells");
  }
}

TYPED_TEST(NeighborSearchGpu, QuerySetAgainstPointSet) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const auto tissue = clusteredCloud<T>(3000, 7);
  auto tool = randomCloud<T>(400, 8);
  for (std::size_t i = 0; i < tool.size(); i += 3) tool[i] = tool[i] * T(3) - Vec3<T>(T(1), T(1), T(1));
  std::vector<T> radii(tool.size());
  for (std::size_t i = 0; i < tool.size(); ++i) radii[i] = T(0.01) + T(0.3) * T(i % 7) / T(7);
  cuda::DeviceBuffer<Vec3<T>> d_tool;
  cuda::DeviceBuffer<T> d_radii, d_one;
  d_tool.upload(tool);
  d_radii.upload(radii);
  d_one.upload(std::vector<T>{T(0.06)});
  const NeighborLists want_one = cpu::bruteForceNeighbors(tool, tissue, std::vector<T>{T(0.06)}, false);
  const NeighborLists want_per = cpu::bruteForceNeighbors(tool, tissue, radii, false);
  for (bool morton : {false, true}) {
    cuda::GridNeighborSearch<T> s;
    s.build(tissue, T(0.06), morton);
    expectSameLists(s.query(d_tool.data(), tool.size(), T(0.06)).download(), want_one, "tool vs tissue, one radius");
    cuda::DeviceNeighborLists out;
    s.query(d_tool.data(), tool.size(), d_one.data(), 1, out);
    expectSameLists(out.download(), want_one, "tool vs tissue, one device radius");
    s.query(d_tool.data(), tool.size(), d_radii.data(), radii.size(), out);
    const NeighborLists got = out.download();
    expectSameLists(got, want_per, "tool vs tissue, per-query radii");
    expectSameLists(got, cpu::GridNeighborSearch<T>(tissue, T(0.06), morton).query(tool, radii), "vs cpu");
    expectCanonical(got, false, "tool vs tissue");
  }
}

TYPED_TEST(NeighborSearchGpu, EmptyAndSinglePointSets) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  cuda::GridNeighborSearch<T> empty;
  empty.build(std::vector<Vec3<T>>{}, T(1));
  EXPECT_EQ(empty.querySelf(T(1)).download().offsets, std::vector<std::int64_t>{0});
  cuda::DeviceBuffer<Vec3<T>> q;
  q.upload(std::vector<Vec3<T>>{Vec3<T>(), Vec3<T>(T(1), T(2), T(3))});
  const NeighborLists e = empty.query(q.data(), 2, T(5)).download();
  EXPECT_EQ(e.offsets, (std::vector<std::int64_t>{0, 0, 0}));
  EXPECT_TRUE(e.indices.empty());
  EXPECT_EQ(empty.query(q.data(), 0, T(5)).download().offsets, std::vector<std::int64_t>{0});

  cuda::GridNeighborSearch<T> one;
  one.build(std::vector<Vec3<T>>{Vec3<T>(T(2), T(2), T(2))}, T(1));
  EXPECT_EQ(one.querySelf(T(1)).download().offsets, (std::vector<std::int64_t>{0, 0}));
  q.upload(std::vector<Vec3<T>>{Vec3<T>(T(2), T(2), T(3)), Vec3<T>(T(2), T(2), T(3.5))});
  const NeighborLists l = one.query(q.data(), 2, T(1)).download();
  EXPECT_EQ(l.offsets, (std::vector<std::int64_t>{0, 1, 1}));
  EXPECT_EQ(l.indices, std::vector<std::int32_t>{0});
}

TYPED_TEST(NeighborSearchGpu, DistanceExactlyRadiusIsIncluded) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const std::vector<Vec3<T>> pts = {Vec3<T>(T(0), T(0), T(0)), Vec3<T>(T(1), T(0), T(0)), Vec3<T>(T(0), T(-1), T(0)),
                                    Vec3<T>(T(1), T(1), T(0)), Vec3<T>(T(1), T(1), T(1)), Vec3<T>(T(0), T(0), T(2))};
  cuda::DeviceBuffer<Vec3<T>> origin;
  origin.upload(std::vector<Vec3<T>>{pts[0]});
  for (T cell : {T(1), T(0.5), T(2)}) {
    cuda::GridNeighborSearch<T> s;
    s.build(pts, cell);
    EXPECT_EQ(s.query(origin.data(), 1, T(1)).download().indices, (std::vector<std::int32_t>{0, 1, 2}));
    EXPECT_EQ(s.query(origin.data(), 1, std::nextafter(T(1), T(0))).download().indices, std::vector<std::int32_t>{0});
    const NeighborLists two = s.querySelf(T(2)).download();
    EXPECT_EQ(std::vector<std::int32_t>(two.indices.begin(), two.indices.begin() + two.offsets[1]),
              (std::vector<std::int32_t>{1, 2, 3, 4, 5}));
  }
}

TYPED_TEST(NeighborSearchGpu, AllPointsInOneCellListEveryOtherPoint) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const std::size_t n = 600;  // rows of 599: the long-row (heap sort) path
  auto pts = randomCloud<T>(n, 9);
  for (auto& x : pts) x = x * T(1e-3);
  for (bool morton : {false, true}) {
    const NeighborLists l = gpuSelf(pts, T(1), T(1), morton);
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

// Storage-order lists: GPU == CPU exactly (offsets and entries), for bucket and Morton order, dense and hashed
// grids, rows longer than the shared-memory column and than the optimistic 32 per query (the second run after
// the index array grows), and a reused output whose capacity already fits.
TYPED_TEST(NeighborSearchGpu, StorageOrderListsEqualTheCpu) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  struct Case {
    std::vector<Vec3<T>> pts;
    T r, cell;
    const char* what;
  };
  auto big = randomCloud<T>(600, 9);
  for (auto& x : big) x = x * T(1e-3);
  const std::vector<Case> cases = {{randomCloud<T>(20000, 31), T(0.03), T(0.015), "random"},
                                   {clusteredCloud<T>(20000, 32), T(0.03), T(0.03), "clustered"},
                                   {latticeCloud<T>(20, 16, 12, T(0.125), 33), T(0.125), T(0.125), "lattice ties"},
                                   {sparseCloud<T>(3000, 34), T(1), T(1), "sparse hashed"},
                                   {big, T(1), T(1), "one cell"}};
  for (const Case& c : cases)
    for (bool morton : {false, true}) {
      const std::string tag = std::string(c.what) + (morton ? " morton" : " bucket-order");
      cpu::GridNeighborSearch<T> cs(c.pts, c.cell, morton);
      const NeighborLists want = cs.querySelfStorage(c.r);
      cuda::GridNeighborSearch<T> gs;
      gs.build(c.pts, c.cell, morton);
      cuda::DeviceNeighborLists out;
      gs.querySelfStorage(c.r, out);
      expectSameLists(out.download(), want, tag + " gpu vs cpu");
      gs.querySelfStorage(c.r, out);  // reused buffers: one run, same lists
      expectSameLists(out.download(), want, tag + " gpu reused vs cpu");
      EXPECT_EQ(downloadArray(gs.sortedToOriginal(), c.pts.size()), cs.sortedToOriginal()) << tag;
    }
}

TYPED_TEST(NeighborSearchGpu, DuplicatePositionsAndZeroRadius) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  auto pts = randomCloud<T>(300, 10);
  for (std::size_t i = 0; i < 40; ++i) pts[100 + i] = pts[7];
  for (T r : {T(0), T(0.05)})
    for (bool morton : {false, true})
      expectSameLists(gpuSelf(pts, r > 0 ? r : T(0.1), r, morton),
                      cpu::bruteForceNeighbors(pts, pts, std::vector<T>{r}, true), "duplicates");
  const NeighborLists zero = gpuSelf(pts, T(0.1), T(0), false);
  EXPECT_EQ(zero.count(7), 40u);
  EXPECT_EQ(zero.count(0), 0u);
}

TYPED_TEST(NeighborSearchGpu, SparseHugeBoxIsHashedLikeTheCpu) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const auto pts = sparseCloud<T>(700, 11);
  cuda::GridNeighborSearch<T> s;
  s.build(pts, T(1));
  const cpu::GridNeighborSearch<T> c(pts, T(1));
  EXPECT_TRUE(s.hashed());
  EXPECT_EQ(s.params().bucket_mask, c.params().bucket_mask);
  for (int a = 0; a < 3; ++a) EXPECT_EQ(s.params().dims[a], c.params().dims[a]);
  EXPECT_LE(s.bucketTableSize(), 4 * pts.size());  // no table of billions of cells
  const NeighborLists got = s.querySelf(T(1)).download();
  expectSameLists(got, cpu::bruteForceNeighbors(pts, pts, std::vector<T>{T(1)}, true), "sparse");
  expectSameLists(got, c.querySelf(T(1)), "sparse vs cpu");
  EXPECT_GT(got.indices.size(), 500u);
  expectSameLists(gpuSelf(pts, T(1), T(1), true), got, "sparse, morton");
}

TYPED_TEST(NeighborSearchGpu, CellsSharingABucketDoNotListAPointTwice) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const CollidingCloud<T> cc = collidingCloud<T>();
  for (bool morton : {false, true}) {
    cuda::GridNeighborSearch<T> s;
    s.build(cc.points, cc.cell, morton);
    ASSERT_TRUE(s.hashed());
    ASSERT_EQ(neighborBucket(s.params(), cc.c1[0], cc.c1[1], cc.c1[2]),
              neighborBucket(s.params(), cc.c2[0], cc.c2[1], cc.c2[2]));
    const NeighborLists l = s.querySelf(cc.radius).download();
    expectSameLists(l, cpu::bruteForceNeighbors(cc.points, cc.points, std::vector<T>{cc.radius}, true), "colliding");
    EXPECT_EQ(std::vector<std::int32_t>(l.indices.begin() + l.offsets[2], l.indices.begin() + l.offsets[3]),
              (std::vector<std::int32_t>{3, 4, 5}));
    expectSameLists(s.querySelf(T(2.5)).download(),
                    cpu::bruteForceNeighbors(cc.points, cc.points, std::vector<T>{T(2.5)}, true), "colliding, r 2.5");
  }
}

TYPED_TEST(NeighborSearchGpu, NonFiniteInputNamesTheEntry) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  auto pts = randomCloud<T>(5000, 12);
  pts[4017].y = std::numeric_limits<T>::quiet_NaN();
  pts[4500].x = std::numeric_limits<T>::infinity();  // the first bad index is the one named
  cuda::GridNeighborSearch<T> s;
  try {
    s.build(pts, T(0.1));
    FAIL() << "NaN point accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "points[4017]");
  }
  pts[4017].y = T(0.5);
  try {
    s.build(pts, T(0.1));
    FAIL() << "infinite point accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "points[4500]");
  }
  pts[4500].x = T(0.5);
  s.build(pts, T(0.1));  // the object is usable after a rejected build
  expectSameLists(s.querySelf(T(0.05)).download(), cpu::GridNeighborSearch<T>(pts, T(0.1)).querySelf(T(0.05)),
                  "after rejected builds");

  // A build from device memory does not wait for the device: the bad point is named by the first call that
  // reads the grid on the host (here each kind of query and check()), and the grid is empty afterwards.
  auto bad_pts = pts;
  bad_pts[1234].z = -std::numeric_limits<T>::infinity();
  cuda::DeviceBuffer<Vec3<T>> d_bad;
  d_bad.upload(bad_pts);
  for (int how = 0; how < 3; ++how) {
    cuda::GridNeighborSearch<T> g;
    g.build(d_bad.data(), bad_pts.size(), T(0.1));
    EXPECT_EQ(g.size(), bad_pts.size());
    cuda::DeviceNeighborLists lists;
    try {
      if (how == 0) g.querySelf(T(0.05), lists);
      if (how == 1) g.querySelfStorage(T(0.05), lists);
      if (how == 2) g.check();
      FAIL() << "infinite point accepted by a device build (" << how << ")";
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), "points[1234]");
    }
    EXPECT_EQ(g.size(), 0u);
    g.querySelfStorage(T(0.05), lists);  // an empty grid: empty lists, no error
    EXPECT_EQ(lists.queryCount(), 0u);
  }
  cuda::GridNeighborSearch<T> m;
  try {
    m.build(d_bad.data(), bad_pts.size(), T(0.1), true);  // Morton order checks inside build
    FAIL() << "infinite point accepted by a Morton build";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "points[1234]");
  }

  std::vector<Vec3<T>> q(4);
  q[2].x = std::numeric_limits<T>::infinity();
  cuda::DeviceBuffer<Vec3<T>> d_q;
  d_q.upload(q);
  try {
    s.query(d_q.data(), q.size(), T(0.1));
    FAIL() << "infinite query accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "queries[2]");
  }
  std::vector<T> radii(pts.size(), T(0.1));
  radii[31] = T(-1);
  radii[40] = std::numeric_limits<T>::quiet_NaN();
  cuda::DeviceBuffer<T> d_r;
  d_r.upload(radii);
  cuda::DeviceNeighborLists out;
  try {
    s.querySelf(d_r.data(), radii.size(), out);
    FAIL() << "negative radius accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "radii[31]");
  }
  EXPECT_THROW(s.querySelf(d_r.data(), 3, out), InputError);  // neither 1 nor n radii
  EXPECT_THROW(s.querySelf(std::numeric_limits<T>::quiet_NaN()), InputError);
  EXPECT_THROW(s.querySelf(std::numeric_limits<T>::infinity()), InputError);
  EXPECT_THROW(s.query(nullptr, 3, T(0.1)), InputError);
  EXPECT_THROW(s.query(d_q.data(), q.size(), nullptr, 1, out), InputError);
  EXPECT_THROW(s.build(nullptr, 10, T(0.1)), InputError);
  s.build(pts, T(0.1));
  EXPECT_THROW(s.build(pts, T(0)), InputError);
  EXPECT_THROW(s.build(pts, std::numeric_limits<T>::denorm_min()), InputError);
  s.build(pts, T(0.1));
  expectSameLists(s.querySelf(T(0.05)).download(), cpu::GridNeighborSearch<T>(pts, T(0.1)).querySelf(T(0.05)),
                  "after rejected queries");
}

TYPED_TEST(NeighborSearchGpu, PermutationsEqualTheCpu) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const auto pts = clusteredCloud<T>(4000, 13);
  for (bool morton : {false, true}) {
    cuda::GridNeighborSearch<T> s;
    s.build(pts, T(0.05), morton);
    const cpu::GridNeighborSearch<T> c(pts, T(0.05), morton);
    // both sorts are stable on the same keys, so the storage orders are identical, not merely equivalent
    EXPECT_EQ(downloadArray(s.sortedToOriginal(), pts.size()), c.sortedToOriginal());
    EXPECT_EQ(downloadArray(s.originalToSorted(), pts.size()), c.originalToSorted());
    const std::vector<Vec3<T>> sorted = downloadArray(s.sortedPoints(), pts.size());
    for (std::size_t i = 0; i < sorted.size(); ++i) {
      ASSERT_EQ(sorted[i].x, c.sortedPoints()[i].x);
      ASSERT_EQ(sorted[i].z, c.sortedPoints()[i].z);
    }
  }
}

TYPED_TEST(NeighborSearchGpu, RebuildReusesBuffersAndRepeatsExactly) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  cuda::GridNeighborSearch<T> s;
  const auto big = clusteredCloud<T>(6000, 15), small = randomCloud<T>(700, 16);
  cuda::DeviceNeighborLists out;
  s.build(big, T(0.04), true);
  s.querySelf(T(0.04), out);
  const NeighborLists first = out.download();
  expectSameLists(first, cpu::bruteForceNeighbors(big, big, std::vector<T>{T(0.04)}, true), "big");
  s.build(small, T(0.1));  // smaller: the larger old buffers must not leak into the lists
  s.querySelf(T(0.1), out);
  expectSameLists(out.download(), cpu::bruteForceNeighbors(small, small, std::vector<T>{T(0.1)}, true), "small");
  s.build(big, T(0.04), true);
  s.querySelf(T(0.04), out);
  expectSameLists(out.download(), first, "repeat is bit-identical");
}

TYPED_TEST(NeighborSearchGpu, LargeCloudEqualsCpu) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  // 200k jittered-lattice points at ~30 neighbours: many blocks, long scans, int64 offsets
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<Vec3<T>> pts;
  const int m = 58;
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) pts.emplace_back(T(i + u(rng)), T(j + u(rng)), T(k + u(rng)));
  const T r = T(1.93);
  for (bool morton : {false, true})
    expectSameLists(gpuSelf(pts, r, r, morton), cpu::GridNeighborSearch<T>(pts, r, morton).querySelf(r), "200k");
}

TYPED_TEST(NeighborSearchGpu, FindNeighborsDispatchAgreesAcrossBackends) {
  SKIP_WITHOUT_GPU();
  using T = TypeParam;
  const auto pts = clusteredCloud<T>(2000, 18);
  const auto tool = randomCloud<T>(100, 19);
  NeighborSearchOptions o;
  o.morton_order = true;
  expectSameLists(findNeighbors(BackendKind::Cuda, pts, T(0.05), o), findNeighbors(BackendKind::Cpu, pts, T(0.05)),
                  "self");
  expectSameLists(findNeighbors(BackendKind::Cuda, tool, pts, std::vector<T>{T(0.07)}),
                  cpu::bruteForceNeighbors(tool, pts, std::vector<T>{T(0.07)}, false), "cross");
}

}  // namespace

#endif  // INCISION_HAVE_CUDA
