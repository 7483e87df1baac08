// PointGrid (host/assembly/point_grid.h) against brute force: nearest member, any and every member within r, queries
// inside and outside the grid's box, a grown cell.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "host/assembly/point_grid.h"

namespace inc {
namespace {

TEST(PointGrid, QueriesEqualBruteForceInsideAndOutsideTheBox) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  std::vector<Vec3d> x;
  for (int i = 0; i < 600; ++i) x.push_back(Vec3d(u(rng), 0.3 * u(rng), u(rng)));
  x.push_back(x[17]);  // a duplicate: the lower index must win the tie
  const Vec3d lo(-0.05, -0.015, -0.05), hi(0.05, 0.015, 0.05);
  // A fine cell (grid of 8 cells at most: the edge grows) and a coarse one; every other point a member.
  for (const std::size_t max_cells : {std::size_t(8), std::size_t(100000)}) {
    PointGrid g(x, lo, hi, 0.004, max_cells);
    if (max_cells == 8) {
      EXPECT_GT(g.cell(), 0.004);
    }
    std::vector<std::int32_t> members;
    for (std::int32_t i = 0; i < std::int32_t(x.size()); i += 2) members.push_back(i);
    members.push_back(std::int32_t(x.size()) - 1);  // the duplicate point, inserted twice: the second is ignored
    for (std::int32_t i : members) g.insert(i);
    for (int q = 0; q < 400; ++q) {
      Vec3d p(u(rng), u(rng), u(rng));
      if (q % 5 == 0) p = p * 3.0;  // far outside the box
      if (q == 1) p = x[17];
      double best = std::numeric_limits<double>::infinity();
      std::int32_t arg = -1;
      for (std::int32_t i : members) {
        const double d = norm(x[std::size_t(i)] - p);
        if (d < best || (d == best && i < arg)) best = d, arg = i;
      }
      double dist = 0;
      ASSERT_EQ(g.nearest(p, dist), arg) << "query " << q;
      ASSERT_EQ(dist, best) << "query " << q;
      for (const double r : {0.001, 0.01, 0.05}) {
        bool any = false;
        for (std::int32_t i : members) any = any || norm(x[std::size_t(i)] - p) <= r;
        ASSERT_EQ(g.anyWithin(p, r), any) << "query " << q << " r " << r;
        std::vector<std::int32_t> within, visited;
        for (std::int32_t i : members)
          if (norm(x[std::size_t(i)] - p) <= r && (within.empty() || within.back() != i)) within.push_back(i);
        g.forEachWithin(p, r, [&](std::int32_t i) {
          visited.push_back(i);
          return true;
        });
        std::sort(visited.begin(), visited.end());
        ASSERT_EQ(visited, within) << "query " << q << " r " << r;
      }
    }
  }
  PointGrid empty(x, lo, hi, 0.01, 1000);
  double d = 0;
  EXPECT_EQ(empty.nearest(Vec3d(), d), -1);
  EXPECT_FALSE(empty.anyWithin(Vec3d(), 1.0));
}

}  // namespace
}  // namespace inc
