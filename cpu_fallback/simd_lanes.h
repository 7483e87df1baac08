// SSE2 lane types (F32x4, F64x2) whose operators are the scalar IEEE operations lane by lane, so that the shared
// physics templates instantiated on them give each lane the scalar code's bits (the build has no FMA).
#pragma once

#if defined(__SSE2__)
#include <emmintrin.h>
#define INC_HAVE_SIMD_LANES 1

namespace inc::cpu {

// Four floats, one per lane (a cluster, a particle).
struct F32x4 {
  using Scalar = float;
  static constexpr int kWidth = 4;
  __m128 v;
  F32x4() : v(_mm_setzero_ps()) {}
  explicit F32x4(float s) : v(_mm_set1_ps(s)) {}  // T(1), T(2) in the shared templates
  explicit F32x4(__m128 x) : v(x) {}
  F32x4& operator+=(F32x4 o) {
    v = _mm_add_ps(v, o.v);
    return *this;
  }
  F32x4& operator-=(F32x4 o) {
    v = _mm_sub_ps(v, o.v);
    return *this;
  }
  F32x4& operator*=(F32x4 o) {
    v = _mm_mul_ps(v, o.v);
    return *this;
  }
  friend F32x4 operator+(F32x4 a, F32x4 b) { return F32x4(_mm_add_ps(a.v, b.v)); }
  friend F32x4 operator-(F32x4 a, F32x4 b) { return F32x4(_mm_sub_ps(a.v, b.v)); }
  friend F32x4 operator*(F32x4 a, F32x4 b) { return F32x4(_mm_mul_ps(a.v, b.v)); }
  friend F32x4 operator/(F32x4 a, F32x4 b) { return F32x4(_mm_div_ps(a.v, b.v)); }
  // A lane mask: all ones where true (the result of a comparison).
  struct Mask {
    __m128 m;
    friend Mask operator&(Mask a, Mask b) { return {_mm_and_ps(a.m, b.m)}; }
    bool any() const { return _mm_movemask_ps(m) != 0; }
    bool lane(int k) const { return (_mm_movemask_ps(m) >> k) & 1; }
  };
  friend Mask operator>(F32x4 a, F32x4 b) { return {_mm_cmpgt_ps(a.v, b.v)}; }  // false for NaN, as the scalar '>'
  friend F32x4 select(Mask k, F32x4 a, F32x4 b) {
    return F32x4(_mm_or_ps(_mm_and_ps(k.m, a.v), _mm_andnot_ps(k.m, b.v)));
  }
  friend F32x4 sqrt(F32x4 a) { return F32x4(_mm_sqrt_ps(a.v)); }                       // sqrtf per lane
  friend F32x4 abs(F32x4 a) { return F32x4(_mm_andnot_ps(_mm_set1_ps(-0.0f), a.v)); }  // fabsf per lane
  static Mask lanesBelow(int count) {                                                  // lanes [0, count)
    const __m128i idx = _mm_setr_epi32(0, 1, 2, 3);
    return {_mm_castsi128_ps(_mm_cmplt_epi32(idx, _mm_set1_epi32(count)))};
  }
  void store(float* out) const { _mm_storeu_ps(out, v); }
  static F32x4 load(const float* in) { return F32x4(_mm_loadu_ps(in)); }
  static F32x4 gather(const float* p, int stride) {  // p[0], p[stride], p[2 stride], p[3 stride]
    return F32x4(_mm_setr_ps(p[0], p[stride], p[2 * stride], p[3 * stride]));
  }
};

// Two doubles, one per lane (float64 models: a batch of four is two of these, stepped in lockstep).
struct F64x2 {
  using Scalar = double;
  static constexpr int kWidth = 2;
  __m128d v;
  F64x2() : v(_mm_setzero_pd()) {}
  explicit F64x2(double s) : v(_mm_set1_pd(s)) {}
  explicit F64x2(__m128d x) : v(x) {}
  F64x2& operator+=(F64x2 o) {
    v = _mm_add_pd(v, o.v);
    return *this;
  }
  F64x2& operator-=(F64x2 o) {
    v = _mm_sub_pd(v, o.v);
    return *this;
  }
  F64x2& operator*=(F64x2 o) {
    v = _mm_mul_pd(v, o.v);
    return *this;
  }
  friend F64x2 operator+(F64x2 a, F64x2 b) { return F64x2(_mm_add_pd(a.v, b.v)); }
  friend F64x2 operator-(F64x2 a, F64x2 b) { return F64x2(_mm_sub_pd(a.v, b.v)); }
  friend F64x2 operator*(F64x2 a, F64x2 b) { return F64x2(_mm_mul_pd(a.v, b.v)); }
  friend F64x2 operator/(F64x2 a, F64x2 b) { return F64x2(_mm_div_pd(a.v, b.v)); }
  struct Mask {
    __m128d m;
    friend Mask operator&(Mask a, Mask b) { return {_mm_and_pd(a.m, b.m)}; }
    bool any() const { return _mm_movemask_pd(m) != 0; }
    bool lane(int k) const { return (_mm_movemask_pd(m) >> k) & 1; }
  };
  friend Mask operator>(F64x2 a, F64x2 b) { return {_mm_cmpgt_pd(a.v, b.v)}; }
  friend F64x2 select(Mask k, F64x2 a, F64x2 b) {
    return F64x2(_mm_or_pd(_mm_and_pd(k.m, a.v), _mm_andnot_pd(k.m, b.v)));
  }
  friend F64x2 sqrt(F64x2 a) { return F64x2(_mm_sqrt_pd(a.v)); }
  friend F64x2 abs(F64x2 a) { return F64x2(_mm_andnot_pd(_mm_set1_pd(-0.0), a.v)); }
  static Mask lanesBelow(int count) {
    return {_mm_castsi128_pd(_mm_cmplt_epi32(_mm_setr_epi32(0, 0, 1, 1), _mm_set1_epi32(count)))};
  }
  void store(double* out) const { _mm_storeu_pd(out, v); }
  static F64x2 load(const double* in) { return F64x2(_mm_loadu_pd(in)); }
  static F64x2 gather(const double* p, int stride) { return F64x2(_mm_setr_pd(p[0], p[stride])); }
};

}  // namespace inc::cpu

#endif
