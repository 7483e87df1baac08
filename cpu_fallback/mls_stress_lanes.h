// The CPU's pass-1 stress of four particles at once, one per SSE2 lane: mlsStressAt's bits for each of them.
#pragma once

#include <cstdint>

#include "cpu_fallback/simd_lanes.h"
#include "physics/mls_passes.h"

namespace inc::cpu {

#if defined(INC_HAVE_SIMD_LANES)
#define INC_HAVE_MLS_STRESS_LANES 1

// Why: after the pair sums, each particle's stress point (strain, SVK stress, Piola stress, the volume term) and
// M = v P A^{-1} are ~400 scalar instructions, about 60 % of the CPU stress pass in the cutting benchmark. Four
// particles in the lanes of one register take the same IEEE operations in the same order (mlsStressPoint and
// mlsStressOutputs instantiated on F32x4, the coefficients broadcast), so every lane has the scalar bits; the
// tests MlsStressLanes.* compare them. The stiffening (the last pass of a batch only) stays scalar per particle.

namespace detail {
// Lanes of entry e of four consecutive 3x3 float records (rec + 9 k): lane k holds rec[9 k + e].
inline void loadLanes9(const float* rec, F32x4 out[9]) {
  for (int half = 0; half < 2; ++half) {
    __m128 r0 = _mm_loadu_ps(rec + 4 * half), r1 = _mm_loadu_ps(rec + 9 + 4 * half);
    __m128 r2 = _mm_loadu_ps(rec + 18 + 4 * half), r3 = _mm_loadu_ps(rec + 27 + 4 * half);
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    out[4 * half + 0] = F32x4(r0);
    out[4 * half + 1] = F32x4(r1);
    out[4 * half + 2] = F32x4(r2);
    out[4 * half + 3] = F32x4(r3);
  }
  out[8] = F32x4(_mm_setr_ps(rec[8], rec[17], rec[26], rec[35]));
}
inline void storeLanes9(const F32x4 in[9], float* rec) {
  for (int half = 0; half < 2; ++half) {
    __m128 r0 = in[4 * half].v, r1 = in[4 * half + 1].v, r2 = in[4 * half + 2].v, r3 = in[4 * half + 3].v;
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    _mm_storeu_ps(rec + 4 * half, r0);
    _mm_storeu_ps(rec + 9 + 4 * half, r1);
    _mm_storeu_ps(rec + 18 + 4 * half, r2);
    _mm_storeu_ps(rec + 27 + 4 * half, r3);
  }
  alignas(16) float last[4];
  in[8].store(last);
  for (int k = 0; k < 4; ++k) rec[9 * k + 8] = last[k];
}
inline Mat3<F32x4> lanesToMat(const F32x4 e[9]) {
  Mat3<F32x4> m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m.m[r][c] = e[3 * r + c];
  return m;
}
}  // namespace detail

// mlsStressAt(s, i0 + k, g[k]) for k = 0..3 (four consecutive particles).
inline void mlsStressAtLanes(const MlsView<float>& s, std::int64_t i0, const Mat3<float> g[4]) {
  static_assert(sizeof(Mat3<float>) == 9 * sizeof(float), "Mat3<float> must be nine packed floats");
  F32x4 e[9];
  detail::loadLanes9(&g[0].m[0][0], e);
  const Mat3<F32x4> gl = detail::lanesToMat(e);
  detail::loadLanes9(&s.moment_inverse[i0].m[0][0], e);
  const Mat3<F32x4> ainv = detail::lanesToMat(e);
  Mat3<F32x4> moment;
  F32x4 energy;
  mlsStressOutputs(mlsStressPoint(gl, s.coeffs), F32x4::load(s.volume + i0), ainv, moment, energy);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) e[3 * r + c] = moment.m[r][c];
  detail::storeLanes9(e, &s.stress_moment[i0].m[0][0]);
  energy.store(s.energy + i0);
  if (s.stiffening)
    for (int k = 0; k < 4; ++k) s.stiffening[i0 + k] = mlsStiffeningOf(g[k], s.coeffs);
}
#endif

}  // namespace inc::cpu
