// The CPU's MLS stress and force passes with the rest pair tables, vectorised within each pair term with AVX2
// (detected at run time) or looped portably; both give the same bits (physics/mls_passes.h defines the order).
#include "cpu_fallback/mls_pair_sums_cpu.h"
#include "cpu_fallback/mls_stress_lanes.h"

#include <atomic>

#if (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__)
#include <immintrin.h>
#define INC_MLS_AVX2 1
// No "fma": a fused multiply-add rounds once where the portable loop (SSE2) rounds twice, and the two paths must
// agree bit for bit.
#define INC_TARGET_AVX2 __attribute__((target("avx2")))
#else
#define INC_MLS_AVX2 0
#endif

namespace inc::cpu {

namespace {

std::atomic<bool> g_portable_only{false};

bool cpuHasAvx2() {
#if INC_MLS_AVX2
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
#else
  return false;
#endif
}

#if INC_MLS_AVX2
// Each pair term is an outer product of two 3-vectors (eq. 5: (u_j - u_i) d^T; eq. 9: M_i entry by entry times
// (w x)^T by columns). Its nine entries, row-major, go into one 8-lane register and one scalar: the lanes hold
// the nine running sums of the portable loop, added in the same order, each product rounded then added (no fma).
// Two sets of sums, the even and the odd slots of a list, as the portable loop keeps them: one chain of
// dependent additions per pair would wait out the adder's latency (~4 cycles) on every pair.
// A vector read of a 3-vector takes 4 floats: the pair tables carry one spare entry at their end, the
// displacements (not padded) are read with a lane mask.

// Pass 1 over [begin, end): the gradient's pair sum G_i = sum_j (u_j - u_i) d_ij^T, then mlsStressAt (four
// particles at a time in SIMD lanes: cpu_fallback/mls_stress_lanes.h).
INC_TARGET_AVX2 void stressRangeAvx2(const MlsView<float>& s, std::int64_t begin, std::int64_t end) {
  const __m128i xyz = _mm_setr_epi32(-1, -1, -1, 0);
  const __m256i rows = _mm256_setr_epi32(0, 0, 0, 1, 1, 1, 2, 2);
  const __m256i cols = _mm256_setr_epi32(0, 1, 2, 0, 1, 2, 0, 1);
  const float* u = &s.displacement[0].x;
  const float* d = &s.pair_gradient[0].x;
  // Gradients of four consecutive particles, then their stress points in SIMD lanes (the scalar bits).
  Mat3<float> batch[4];
  std::int64_t first = begin;
  for (std::int64_t i = begin; i < end; ++i) {
    const __m128 ui = _mm_maskload_ps(u + 3 * i, xyz);
    __m256 acc[2] = {_mm256_setzero_ps(), _mm256_setzero_ps()};
    __m128 acc8[2] = {_mm_setzero_ps(), _mm_setzero_ps()};
    const auto add = [&](std::int64_t p, int q) INC_TARGET_AVX2 {
      const __m128 du = _mm_sub_ps(_mm_maskload_ps(u + 3 * std::int64_t(s.indices[p]), xyz), ui);
      const __m128 dp = _mm_loadu_ps(d + 3 * p);
      acc[q] = _mm256_add_ps(acc[q], _mm256_mul_ps(_mm256_permutevar8x32_ps(_mm256_castps128_ps256(du), rows),
                                                   _mm256_permutevar8x32_ps(_mm256_castps128_ps256(dp), cols)));
      acc8[q] = _mm_add_ss(acc8[q], _mm_mul_ss(_mm_movehl_ps(du, du), _mm_movehl_ps(dp, dp)));
    };
    const std::int64_t e = s.offsets[i + 1];
    std::int64_t p = s.offsets[i];
    for (; p + 1 < e; p += 2) {
      add(p, 0);
      add(p + 1, 1);
    }
    if (p < e) add(p, 0);
    Mat3<float>& g = batch[i - first];
    _mm256_storeu_ps(&g.m[0][0], _mm256_add_ps(acc[0], acc[1]));
    _mm_store_ss(&g.m[2][2], _mm_add_ss(acc8[0], acc8[1]));
    if (i - first == 3) {
      mlsStressAtLanes(s, first, batch);
      first = i + 1;
    }
  }
  for (std::int64_t i = first; i < end; ++i) mlsStressAt(s, i, batch[i - first]);
}

// Pass 2 over [begin, end): a_rc = sum_i (M_i)_rc (w x)_c, then mlsForceFromPairSum and mlsForceAt.
INC_TARGET_AVX2 void forceRangeAvx2(const MlsView<float>& s, std::int64_t begin, std::int64_t end, float half_dt,
                                    bool kick) {
  const __m256i cols = _mm256_setr_epi32(0, 1, 2, 0, 1, 2, 0, 1);
  const float* wx = &s.pair_force[0].x;
  const float* m = &s.stress_moment[0].m[0][0];
  for (std::int64_t k = begin; k < end; ++k) {
    __m256 acc[2] = {_mm256_setzero_ps(), _mm256_setzero_ps()};
    __m128 acc8[2] = {_mm_setzero_ps(), _mm_setzero_ps()};
    const auto add = [&](std::int64_t p, int q) INC_TARGET_AVX2 {
      const float* mi = m + 9 * std::int64_t(s.indices[p]);
      const __m128 w = _mm_loadu_ps(wx + 3 * p);
      acc[q] = _mm256_add_ps(
          acc[q], _mm256_mul_ps(_mm256_loadu_ps(mi), _mm256_permutevar8x32_ps(_mm256_castps128_ps256(w), cols)));
      acc8[q] = _mm_add_ss(acc8[q], _mm_mul_ss(_mm_load_ss(mi + 8), _mm_movehl_ps(w, w)));
    };
    const std::int64_t e = s.offsets[k + 1];
    std::int64_t p = s.offsets[k];
    for (; p + 1 < e; p += 2) {
      add(p, 0);
      add(p + 1, 1);
    }
    if (p < e) add(p, 0);
    Mat3<float> a;
    _mm256_storeu_ps(&a.m[0][0], _mm256_add_ps(acc[0], acc[1]));
    _mm_store_ss(&a.m[2][2], _mm_add_ss(acc8[0], acc8[1]));
    mlsForceAt(s, k, mlsForceFromPairSum(s.stress_moment[k], s.weighted_sum[k], a), half_dt, kick);
  }
}
#endif

}  // namespace

bool mlsPairSumsUseAvx2() { return !g_portable_only && cpuHasAvx2(); }
void setMlsPairSumsPortable(bool portable_only) { g_portable_only = portable_only; }

template <typename T>
void mlsStressRange(const MlsView<T>& s, std::int64_t begin, std::int64_t end, bool avx2) {
#if INC_MLS_AVX2
  if constexpr (sizeof(T) == 4) {
    if (avx2 && s.pair_gradient) return stressRangeAvx2(s, begin, end);
  }
#endif
  (void)avx2;
  std::int64_t i = begin;
#if defined(INC_HAVE_MLS_STRESS_LANES)
  if constexpr (sizeof(T) == 4) {
    for (; i + 4 <= end; i += 4) {
      const Mat3<float> g[4] = {mlsDisplacementGradient(s, i), mlsDisplacementGradient(s, i + 1),
                                mlsDisplacementGradient(s, i + 2), mlsDisplacementGradient(s, i + 3)};
      mlsStressAtLanes(s, i, g);
    }
  }
#endif
  for (; i < end; ++i) mlsStressPass(s, i);
}

template <typename T>
void mlsForceRange(const MlsView<T>& s, std::int64_t begin, std::int64_t end, T half_dt, bool kick, bool avx2) {
#if INC_MLS_AVX2
  if constexpr (sizeof(T) == 4) {
    if (avx2 && s.pair_force) return forceRangeAvx2(s, begin, end, half_dt, kick);
  }
#endif
  (void)avx2;
  for (std::int64_t k = begin; k < end; ++k) mlsForcePass(s, k, half_dt, kick);
}

template void mlsStressRange<float>(const MlsView<float>&, std::int64_t, std::int64_t, bool);
template void mlsStressRange<double>(const MlsView<double>&, std::int64_t, std::int64_t, bool);
template void mlsForceRange<float>(const MlsView<float>&, std::int64_t, std::int64_t, float, bool, bool);
template void mlsForceRange<double>(const MlsView<double>&, std::int64_t, std::int64_t, double, bool, bool);

}  // namespace inc::cpu
