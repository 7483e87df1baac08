// Cut tests on the GPU: the sphere mask and the crossing-pair mask equal the CPU decisions exactly.
#if INCISION_HAVE_CUDA
#include <gtest/gtest.h>

#include <cmath>

#include "cpu_fallback/neighbor_bruteforce.h"
#include "host/cut_nodal_points.h"
#include "kernels/cut_cuda.h"
#include "kernels/device_info.h"
#include "tests/cut_fixtures.h"

using namespace inc;

namespace {

bool noDevice() { return inc::cuda::queryDevices().device_count == 0; }

SweptSurface curvedCut() {
  std::vector<BladePose> poses;
  for (int k = 0; k <= 10; ++k) {
    const double x = -0.08 + 0.016 * k, z = 0.006 * std::sin(0.6 * k);
    poses.push_back({Vec3d(x, -0.1, z - 0.01), Vec3d(x, 0.1, z + 0.012)});
  }
  return sweepSurface(poses);
}

TEST(CutGpu, SphereMaskEqualsCpu) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  const MetaballModel m = cuttest::latticeBlock(16, 10, 8);
  const SweptSurface s = curvedCut();
  const auto cpu = findCutSpheres(s, m.rest_centers, m.rest_radii);
  const auto mask = cuda::cutSphereMaskCuda(s.vertices, s.triangles, m.rest_centers, m.rest_radii);
  ASSERT_EQ(mask.size(), m.size());
  std::vector<std::int32_t> gpu;
  for (std::size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) gpu.push_back(std::int32_t(i));
  EXPECT_GT(cpu.size(), 0u);
  EXPECT_EQ(gpu, cpu);
}

TEST(CutGpu, CrossingPairMaskEqualsCpu) {
  if (noDevice()) GTEST_SKIP() << "no CUDA device";
  const MetaballModel m = cuttest::latticeBlock(16, 10, 8);
  const SweptSurface s = curvedCut();
  const SphereCutResult r = cutSpheres(m, s);
  const NeighborLists all =
      cpu::bruteForceNeighbors(r.points.positions, r.points.positions, std::vector<double>{2.5 * r.points.spacing}, true);
  const auto mask = cuda::crossingPairMaskCuda(s.vertices, s.triangles, r.points.positions, all.offsets, all.indices);
  ASSERT_EQ(mask.size(), all.indices.size());
  std::size_t crossing = 0;
  for (std::size_t q = 0; q < all.queryCount(); ++q)
    for (auto k = all.offsets[q]; k < all.offsets[q + 1]; ++k) {
      const bool c = segmentCrossesSweptSurface(s, r.points.positions[q], r.points.positions[all.indices[k]]);
      ASSERT_EQ(bool(mask[k]), c) << "query " << q << " entry " << k;
      crossing += c;
    }
  EXPECT_GT(crossing, 0u);
}

}  // namespace
#endif
