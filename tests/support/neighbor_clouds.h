// Test clouds for the neighbour searches (random, clustered, lattice, sparse, colliding) and a list comparator.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "model/neighbor_lists.h"
#include "physics/neighbor_grid.h"
#include "physics/vec3.h"

namespace inc::testing_neighbors {

// Uniform in [0, 1]^3.
template <typename T>
std::vector<Vec3<T>> randomCloud(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3<T>> p(n);
  for (auto& x : p) x = Vec3<T>(T(u(rng)), T(u(rng)), T(u(rng)));
  return p;
}

// Gaussian blobs of very different widths (dense cores hold hundreds of neighbours) plus a uniform haze.
template <typename T>
std::vector<Vec3<T>> clusteredCloud(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double sigma[4] = {0.004, 0.02, 0.05, 0.1};
  Vec3<double> centre[4];
  for (auto& c : centre) c = Vec3<double>(u(rng), u(rng), u(rng));
  std::vector<Vec3<T>> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 5 == 4) {
      p[i] = Vec3<T>(T(u(rng)), T(u(rng)), T(u(rng)));
      continue;
    }
    const int k = int(i % 4);
    std::normal_distribution<double> g(0.0, sigma[k]);
    p[i] = Vec3<T>(T(centre[k].x + g(rng)), T(centre[k].y + g(rng)), T(centre[k].z + g(rng)));
  }
  return p;
}

// Regular lattice of spacing h (many pairs at exactly h, h sqrt 2, ... : ties at the ball's boundary),
// listed in a shuffled order so that storage order and original order differ.
template <typename T>
std::vector<Vec3<T>> latticeCloud(int nx, int ny, int nz, T h, unsigned seed) {
  std::vector<Vec3<T>> p;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) p.emplace_back(T(i) * h, T(j) * h, T(k) * h);
  std::mt19937 rng(seed);
  std::shuffle(p.begin(), p.end(), rng);
  return p;
}

// n random points in a cube of side 1e-3: with a cell size and radius of order 1, all in one cell and every
// point a neighbour of every other (rows of n - 1).
template <typename T>
std::vector<Vec3<T>> oneCellCloud(std::size_t n, unsigned seed) {
  std::vector<Vec3<T>> p = randomCloud<T>(n, seed);
  for (auto& x : p) x = x * T(1e-3);
  return p;
}

// A cloud with the radius and cell size to search it with, and a name for failure messages.
template <typename T>
struct NeighborCase {
  std::vector<Vec3<T>> pts;
  T r, cell;
  const char* what;
};

// A few tight pairs and triples scattered over a box of side 2e6 (cell size ~1: far too many cells for a
// dense grid, so the search must hash).
template <typename T>
std::vector<Vec3<T>> sparseCloud(std::size_t groups, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1e6, 1e6), v(-0.6, 0.6);
  std::vector<Vec3<T>> p;
  for (std::size_t g = 0; g < groups; ++g) {
    const Vec3<double> c(u(rng), u(rng), u(rng));
    const int members = 1 + int(g % 3);
    for (int m = 0; m < members; ++m) p.emplace_back(T(c.x + v(rng)), T(c.y + v(rng)), T(c.z + v(rng)));
  }
  return p;
}

// Six points in a box of side 1e7 with cell size 1 and radius 1, so the grid hashes into 16 buckets: the 27
// cells around the centre point must share buckets, and two of them (c1, c2, both holding a point within the
// radius of the centre) are chosen to share one. A search that scanned that bucket once per cell without
// filtering by cell would list both points twice.
template <typename T>
struct CollidingCloud {
  std::vector<Vec3<T>> points;
  std::int32_t c1[3], c2[3];
  T cell = T(1), radius = T(1);
};

template <typename T>
CollidingCloud<T> collidingCloud() {
  CollidingCloud<T> cc;
  const Vec3<T> lo(T(0), T(0), T(0)), hi(T(1e7), T(1e7), T(1e7));
  const NeighborGridParams<T> p = makeNeighborGridParams(lo, hi, cc.cell, neighborBucketCount(6), 6, true);
  EXPECT_EQ(p.dense, 0) << "the colliding cloud must be hashed";
  bool found = false;
  for (int a = 0; a < 27 && !found; ++a)
    for (int b = a + 1; b < 27 && !found; ++b) {
      const std::int32_t da[3] = {a % 3 - 1, (a / 3) % 3 - 1, a / 9 - 1},
                         db[3] = {b % 3 - 1, (b / 3) % 3 - 1, b / 9 - 1};
      if (neighborBucket(p, 5 + da[0], 5 + da[1], 5 + da[2]) != neighborBucket(p, 5 + db[0], 5 + db[1], 5 + db[2]))
        continue;
      for (int k = 0; k < 3; ++k) {
        cc.c1[k] = 5 + da[k];
        cc.c2[k] = 5 + db[k];
      }
      found = true;
    }
  EXPECT_TRUE(found) << "27 cells in 16 buckets always collide";
  const T c = T(5.5), s = T(0.55);  // centre of cell (5,5,5); 0.55 steps land inside the neighbour cells
  cc.points = {lo,
               hi,
               Vec3<T>(c, c, c),
               Vec3<T>(c + s * T(cc.c1[0] - 5), c + s * T(cc.c1[1] - 5), c + s * T(cc.c1[2] - 5)),
               Vec3<T>(c + s * T(cc.c2[0] - 5), c + s * T(cc.c2[1] - 5), c + s * T(cc.c2[2] - 5)),
               Vec3<T>(T(5.3), T(5.6), T(5.4))};
  return cc;
}

// Lists must be identical: same offsets, same indices in the same (ascending) order.
inline void expectSameLists(const NeighborLists& got, const NeighborLists& want, const std::string& what) {
  ASSERT_EQ(got.offsets.size(), want.offsets.size()) << what;
  ASSERT_EQ(got.indices.size(), want.indices.size()) << what;
  for (std::size_t q = 0; q + 1 < want.offsets.size(); ++q) {
    ASSERT_EQ(got.offsets[q + 1], want.offsets[q + 1]) << what << ": query " << q << " neighbour count";
  }
  for (std::size_t e = 0; e < want.indices.size(); ++e)
    ASSERT_EQ(got.indices[e], want.indices[e]) << what << ": entry " << e;
}

// Lists are strictly ascending per query (no duplicates) and never contain the query itself when self.
inline void expectCanonical(const NeighborLists& l, bool self, const std::string& what) {
  for (std::size_t q = 0; q < l.queryCount(); ++q)
    for (std::int64_t e = l.offsets[q]; e < l.offsets[q + 1]; ++e) {
      if (e > l.offsets[q]) {
        ASSERT_LT(l.indices[std::size_t(e - 1)], l.indices[std::size_t(e)]) << what << " query " << q;
      }
      if (self) {
        ASSERT_NE(std::size_t(l.indices[std::size_t(e)]), q) << what;
      }
    }
}

// Storage-order lists (row s = storage slot s, entries = storage slots) mapped back through the permutation
// slot -> original index: row perm[s] holds perm[j] for j in row s, sorted. Equal to the original-order lists
// when both name the same pairs.
inline NeighborLists storageListsToOriginal(const NeighborLists& storage, const std::vector<std::int32_t>& perm) {
  const std::size_t n = storage.queryCount();
  NeighborLists out;
  out.offsets.assign(n + 1, 0);
  for (std::size_t s = 0; s < n; ++s) out.offsets[std::size_t(perm[s]) + 1] = std::int64_t(storage.count(s));
  for (std::size_t q = 0; q < n; ++q) out.offsets[q + 1] += out.offsets[q];
  out.indices.resize(storage.indices.size());
  for (std::size_t s = 0; s < n; ++s) {
    std::int32_t* dst = out.indices.data() + out.offsets[std::size_t(perm[s])];
    for (std::int64_t e = storage.offsets[s]; e < storage.offsets[s + 1]; ++e)
      *dst++ = perm[std::size_t(storage.indices[std::size_t(e)])];
    std::sort(out.indices.data() + out.offsets[std::size_t(perm[s])], dst);
  }
  return out;
}

}  // namespace inc::testing_neighbors
