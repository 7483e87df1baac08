// The CPU's MLS stress points in SIMD lanes (cpu_fallback/mls_stress_lanes.h) against the scalar mlsStressAt: the same
// bits for any gradient.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "cpu_fallback/mls_stress_lanes.h"
#include "physics/mls_passes.h"

using namespace inc;

namespace {

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Gradients a cut organ produces and ones it should not: small strains (float's relative accuracy matters most
// there), large stretches and shears, inverted neighbourhoods (det F < 0), the zero gradient, non-finite entries.
std::vector<Mat3<float>> testGradients(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Mat3<float>> out;
  for (double scale : {1e-6, 1e-3, 0.1, 1.0, 3.0})
    for (int i = 0; i < 64; ++i) {
      Mat3<float> g;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) g.m[r][c] = float(scale * u(rng));
      out.push_back(g);
    }
  out.push_back(Mat3<float>());
  out.push_back(Mat3<float>::diag(-2.0f));  // F = -I: inverted
  Mat3<float> bad;
  bad.m[1][2] = std::numeric_limits<float>::quiet_NaN();
  out.push_back(bad);
  bad.m[1][2] = std::numeric_limits<float>::infinity();
  out.push_back(bad);
  out.push_back(Mat3<float>::diag(1e20f));
  return out;
}

#if defined(INC_HAVE_MLS_STRESS_LANES)
// Every gradient through the lanes (four at a time, each lane in every position) and through the scalar code,
// with and without the volume term and the stiffening output: M, the energy and the stiffening bit for bit.
TEST(MlsStressLanes, FourParticlesInLanesGiveTheScalarBits) {
  std::mt19937 rng(17);
  const std::vector<Mat3<float>> grads = testGradients(rng);
  const std::size_t n = grads.size();
  std::uniform_real_distribution<double> u(0.5, 2.0), v(-1.0, 1.0);
  std::vector<float> volume(n);
  std::vector<Mat3<float>> ainv(n);
  for (std::size_t i = 0; i < n; ++i) {
    volume[i] = float(1e-9 * u(rng));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) ainv[i].m[r][c] = float(30.0 * v(rng)) + (r == c ? 100.0f : 0.0f);
  }
  int compared = 0;
  for (const bool volume_term : {false, true})
    for (const bool stiffening : {false, true})
      for (std::size_t shift = 0; shift < 4; ++shift) {
        MlsView<float> s;
        s.n = std::int64_t(n);
        s.volume = volume.data();
        s.moment_inverse = ainv.data();
        s.coeffs = mlsSplitCoefficients(3e4f, 0.45f, volume_term, 1.0f, 0.0f);
        std::vector<Mat3<float>> m_lane(n), m_scalar(n);
        std::vector<float> e_lane(n), e_scalar(n), k_lane(n, -1.0f), k_scalar(n, -1.0f);
        // Scalar reference.
        s.stress_moment = m_scalar.data();
        s.energy = e_scalar.data();
        s.stiffening = stiffening ? k_scalar.data() : nullptr;
        for (std::size_t i = 0; i < n; ++i) mlsStressAt(s, std::int64_t(i), grads[i]);
        // Lanes from `shift` on, so that each gradient visits every lane position across the shifts.
        s.stress_moment = m_lane.data();
        s.energy = e_lane.data();
        s.stiffening = stiffening ? k_lane.data() : nullptr;
        std::size_t i = 0;
        for (; i < shift; ++i) mlsStressAt(s, std::int64_t(i), grads[i]);
        for (; i + 4 <= n; i += 4) cpu::mlsStressAtLanes(s, std::int64_t(i), &grads[i]);
        for (; i < n; ++i) mlsStressAt(s, std::int64_t(i), grads[i]);
        for (std::size_t k = 0; k < n; ++k) {
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c)
              ASSERT_TRUE(sameBits(m_lane[k].m[r][c], m_scalar[k].m[r][c]))
                  << "particle " << k << " M(" << r << "," << c << ") " << m_lane[k].m[r][c] << " vs "
                  << m_scalar[k].m[r][c];
          ASSERT_TRUE(sameBits(e_lane[k], e_scalar[k])) << "particle " << k << " energy";
          ASSERT_TRUE(sameBits(k_lane[k], k_scalar[k])) << "particle " << k << " stiffening";
          ++compared;
        }
      }
  EXPECT_EQ(compared, int(16 * n));
}
#endif

}  // namespace
