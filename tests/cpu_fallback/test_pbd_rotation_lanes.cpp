// The CPU's rotation extraction in SIMD lanes (cpu_fallback/pbd_rotation_lanes.h) against the scalar
// pbd::extractRotations: the same bits for any matrix (whole frames: PbdSolver.CpuLoopsMatchSharedScalarCodeBitForBit).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "cpu_fallback/pbd_rotation_lanes.h"
#include "physics/pbd_rotation.h"

using namespace inc;

namespace {

// Matrices a shape-matching frame can produce, and ones it should not but might: random stretches of random
// rotations, reflections (det < 0), rank 2 and rank 1 (flat and collinear neighbourhoods), the zero matrix, tiny and
// huge scales, an exact rotation (the first step is below eps), non-finite entries.
template <typename T>
std::vector<Mat3<T>> testMatrices(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto randomMat = [&] {
    Mat3<T> a;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) a.m[r][c] = T(u(rng));
    return a;
  };
  auto randomRot = [&] {
    Vec3<T> axis(T(u(rng)), T(u(rng)), T(u(rng)));
    axis *= T(1) / norm(axis);
    return pbd::quatToMatrix(pbd::quatFromAxisAngle(axis, T(3.0 * u(rng))));
  };
  std::vector<Mat3<T>> out;
  for (int i = 0; i < 200; ++i) out.push_back(randomMat());
  for (int i = 0; i < 100; ++i) {  // R S with S near the identity: the usual, nearly converged case
    Mat3<T> s = Mat3<T>::identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) s.m[r][c] += T(0.05 * u(rng));
    out.push_back(randomRot() * s);
  }
  Mat3<T> flip = Mat3<T>::identity();
  flip.m[0][0] = T(-1);
  for (int i = 0; i < 50; ++i) out.push_back(randomRot() * flip);  // reflections
  for (int i = 0; i < 50; ++i) {                                   // rank 2, rank 1, near singular
    Mat3<T> a = randomMat();
    for (int c = 0; c < 3; ++c) a.m[2][c] = i % 3 == 0 ? T(0) : a.m[0][c] * T(0.5) + a.m[1][c] * T(2);
    if (i % 2 == 0)
      for (int c = 0; c < 3; ++c) a.m[1][c] = a.m[0][c] * T(-3);
    if (i % 5 == 0) a.m[2][2] += T(1e-7);
    out.push_back(a);
  }
  out.push_back(Mat3<T>());               // zero
  out.push_back(Mat3<T>::identity());     // a rotation: converged at once from the identity
  out.push_back(randomRot());             // a rotation from elsewhere
  out.push_back(randomMat() * T(1e-30));  // tiny
  out.push_back(randomMat() * T(1e30));   // huge
  Mat3<T> bad = randomMat();
  bad.m[1][2] = std::numeric_limits<T>::quiet_NaN();
  out.push_back(bad);
  bad = randomMat();
  bad.m[0][0] = std::numeric_limits<T>::infinity();
  out.push_back(bad);
  return out;
}

template <typename T>
pbd::Quat<T> randomQuat(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return pbd::quatNormalized(pbd::Quat<T>{T(u(rng)), T(u(rng)), T(u(rng)), T(u(rng))});
}

template <typename T>
bool sameBits(const pbd::Quat<T>& a, const pbd::Quat<T>& b) {
  return std::memcmp(&a, &b, sizeof(a)) == 0;
}

template <typename T>
void expectLanesMatchScalar() {
  std::mt19937 rng(12345);
  const std::vector<Mat3<T>> mats = testMatrices<T>(rng);
  std::uniform_int_distribution<std::size_t> pick(0, mats.size() - 1);
  int batches = 0, steps_changed = 0;
  for (int iterations : {1, 2, 4, 8, 60})
    for (int count = 1; count <= cpu::kRotationLaneBatch; ++count)
      for (std::size_t first = 0; first < mats.size(); first += std::size_t(count)) {
        Mat3<T> a[cpu::kRotationLaneBatch];
        pbd::Quat<T> q0[cpu::kRotationLaneBatch], want[cpu::kRotationLaneBatch], got[cpu::kRotationLaneBatch];
        for (int k = 0; k < count; ++k) {
          // every matrix once in order, the other lanes random: each matrix meets converged, stalled and live
          // neighbours; warm starts at the identity, random, or a previous answer
          a[k] = k == 0 ? mats[first] : mats[pick(rng)];
          q0[k] = (first + std::size_t(k)) % 3 == 0 ? pbd::Quat<T>{} : randomQuat<T>(rng);
        }
        for (int k = 0; k < count; ++k) want[k] = got[k] = q0[k];
        pbd::extractRotations(a, want, count, iterations);
        cpu::extractRotationsLanes<typename cpu::RotationLanesOf<T>::type>(a, got, count, iterations);
        for (int k = 0; k < count; ++k) {
          ASSERT_TRUE(sameBits(want[k], got[k]))
              << "batch of " << count << ", lane " << k << ", " << iterations << " iterations, matrix " << first
              << ": scalar (" << want[k].w << ", " << want[k].x << ", " << want[k].y << ", " << want[k].z << ") lanes ("
              << got[k].w << ", " << got[k].x << ", " << got[k].y << ", " << got[k].z << ")";
          steps_changed += sameBits(q0[k], want[k]) ? 0 : 1;
        }
        ++batches;
      }
  std::printf("%d batches, %d extractions that moved the rotation: lanes == scalar bit for bit\n", batches,
              steps_changed);
  EXPECT_GT(steps_changed, batches);  // the comparison is not only of untouched quaternions
}

}  // namespace

#if defined(INC_HAVE_ROTATION_LANES)
// Every lane of extractRotationsLanes equals pbd::extractRotations (the scalar step, as the GPU runs it) bit for bit,
// whatever its neighbours do: batches of 1-4, 1-60 steps, degenerate and non-finite matrices.
TEST(PbdRotationLanes, FloatLanesMatchScalarExtractionBitForBit) { expectLanesMatchScalar<float>(); }
TEST(PbdRotationLanes, DoubleLanesMatchScalarExtractionBitForBit) { expectLanesMatchScalar<double>(); }
#endif
