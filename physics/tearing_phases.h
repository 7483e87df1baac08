// The per-particle and per-triangle bodies of the tearing step, shared verbatim by the CPU loops and the CUDA kernels.
#pragma once

#include <cstdint>

#include "physics/hd.h"
#include "physics/tearing_tresca.h"
#include "physics/vec3.h"

namespace inc::tear {

enum : int { kThreshold = 0, kTrescaBonds = 1, kTrescaPrincipal = 2 };

// Raw view of a sheet (host or device pointers). tris holds 3 particle indices per triangle.
template <typename T>
struct SheetView {
  Vec3<T>* rest = nullptr;
  Vec3<T>* x = nullptr;
  Vec3<T>* v = nullptr;
  T* mass = nullptr;
  std::uint8_t* fixed = nullptr;
  T* k = nullptr;
  T* tau_f = nullptr;
  std::int32_t* tris = nullptr;
  const std::int32_t* pe_offsets = nullptr;  // particle -> bond partners
  const std::int32_t* pe_partner = nullptr;
  const std::int32_t* pt_offsets = nullptr;  // particle -> triangles
  const std::int32_t* pt_tris = nullptr;
};

template <typename T>
INC_HD Vec3<T> triCentroid(const Vec3<T>* x, const std::int32_t* tri) {
  return (x[tri[0]] + x[tri[1]] + x[tri[2]]) * (T(1) / T(3));
}

template <typename T>
struct Detection {
  std::uint8_t yield = 0;
  std::int32_t partner = -1;
  Vec3<T> dir;  // unit, towards the partner's side
  T t_pred = T(0);
};

// Phase 1. Criterion per docs/tearing.md; a yield only counts when the split plane separates i's
// triangles (some, not all, on the crack side).
template <typename T>
INC_HD Detection<T> detectYield(const SheetView<T>& s, std::int32_t i, int criterion, T break_strain) {
  Detection<T> d;
  StrainExtrema<T> e;
  Mat3<T> sigma;
  const Vec3<T> xi = s.x[i];
  const T ki = s.k[i];
  for (std::int32_t q = s.pe_offsets[i]; q < s.pe_offsets[i + 1]; ++q) {
    const std::int32_t j = s.pe_partner[q];
    const T rest = norm(s.rest[i] - s.rest[j]);
    accumulateStrain(e, bondStrain(xi, s.x[j], rest), j);
    if (criterion == kTrescaPrincipal) accumulateBondStress(sigma, xi, s.x[j], rest, ki);
  }
  if (e.count == 0) return d;
  bool y = false;
  T smax = T(0), smin = T(0);
  Vec3<T> dir = s.x[e.partner_max] - xi;
  if (criterion == kThreshold) {
    y = thresholdYield(e, break_strain);
  } else if (criterion == kTrescaBonds) {
    y = trescaYield(e, ki, s.tau_f[i]);
    smax = ki * e.rho_max;
    smin = ki * e.rho_min;
  } else {
    sigma *= T(1) / T(e.count);
    T s1, s2, s3;
    symmetricEigenvalues(sigma, s1, s2, s3);
    y = e.count >= 2 && trescaShearOfPrincipals(s1, s3) >= s.tau_f[i];
    smax = s1;
    smin = s3;
    if (y) {
      Vec3<T> pd = symmetricEigenvector(sigma, s1);
      if (norm2(pd) > T(0)) {
        if (dot(pd, dir) < T(0)) pd = -pd;
        dir = pd;
      }
    }
  }
  if (!y) return d;
  const T ld = norm(dir);
  if (!(ld > T(0))) return d;
  dir *= T(1) / ld;
  int moved = 0, total = 0;
  for (std::int32_t q = s.pt_offsets[i]; q < s.pt_offsets[i + 1]; ++q) {
    ++total;
    if (onSplitSide(triCentroid(s.x, s.tris + 3 * s.pt_tris[q]), xi, dir)) ++moved;
  }
  if (moved == 0 || moved == total) return d;
  d.yield = 1;
  d.partner = e.partner_max;
  d.dir = dir;
  d.t_pred = criterion == kThreshold ? T(0) : predictedFraction(smax, smin);
  return d;
}

// Phase 2: i splits this step when it yields and has the highest priority among the yielding particles that
// share a triangle with it, so the triangles each split rewrites are disjoint (an independent set, chosen by
// a gather). The priority is a hash of (seed, particle, step), ties by index: integer, so both backends pick
// the same set, and unbiased by the numbering (an index order would let only local index minima split).
INC_HD std::uint64_t splitPriority(std::uint32_t seed, std::int32_t i, std::uint32_t step) {
  return (std::uint64_t(tearHash(seed ^ 0x5bd1e995U, std::uint32_t(i), 0x27d4eb2dU, step)) << 32) | std::uint32_t(i);
}

template <typename T>
INC_HD std::uint8_t acceptSplit(const SheetView<T>& s, const std::uint8_t* yield, std::int32_t i, std::uint32_t seed,
                                std::uint32_t step) {
  if (!yield[i]) return 0;
  const std::uint64_t mine = splitPriority(seed, i, step);
  for (std::int32_t q = s.pt_offsets[i]; q < s.pt_offsets[i + 1]; ++q) {
    const std::int32_t* tri = s.tris + 3 * s.pt_tris[q];
    for (int c = 0; c < 3; ++c)
      if (tri[c] != i && yield[tri[c]] && splitPriority(seed, tri[c], step) > mine) return 0;
  }
  return 1;
}

struct SplitResult {
  int moved_triangles = 0;
  int backed_off = 0;
};

// Phase 4: new particle n_idx for accepted particle i. Position and rest position at fraction t of the way
// to the partner j (t = 0: traditional duplicate); t is halved until every moved triangle keeps its
// orientation and min_ratio of its area in both configurations (0 after 4 halvings). Mass split by the
// rest areas of the two triangle groups; the new particle takes i's velocity (mass and momentum conserved).
template <typename T>
INC_HD SplitResult splitParticle(const SheetView<T>& s, std::int32_t i, std::size_t n_idx, std::int32_t j,
                                 const Vec3<T>& dir, T t_pred, bool debris, T range, T t_lo, T t_hi, T min_ratio,
                                 std::uint32_t seed, std::uint32_t step) {
  SplitResult r;
  T t = T(0);
  if (debris) {
    const std::uint32_t a = std::uint32_t(i < j ? i : j), b = std::uint32_t(i < j ? j : i);
    t = perturbedFraction(t_pred, range, tearUniform<T>(seed, a, b, step), t_lo, t_hi);
  }
  const Vec3<T> xi = s.x[i], ri = s.rest[i];
  T area_move = T(0), area_all = T(0);
  for (std::int32_t q = s.pt_offsets[i]; q < s.pt_offsets[i + 1]; ++q) {
    const std::int32_t* tri = s.tris + 3 * s.pt_tris[q];
    const T a = norm(triangleAreaVector(s.rest[tri[0]], s.rest[tri[1]], s.rest[tri[2]]));
    area_all += a;
    if (onSplitSide(triCentroid(s.x, tri), xi, dir)) {
      area_move += a;
      ++r.moved_triangles;
    }
  }
  for (int attempt = 0; attempt <= 4 && t > T(0); ++attempt) {
    const Vec3<T> nx = xi + (s.x[j] - xi) * t, nr = ri + (s.rest[j] - ri) * t;
    bool ok = true;
    for (std::int32_t q = s.pt_offsets[i]; q < s.pt_offsets[i + 1] && ok; ++q) {
      const std::int32_t* tri = s.tris + 3 * s.pt_tris[q];
      if (!onSplitSide(triCentroid(s.x, tri), xi, dir)) continue;
      const int c = tri[0] == i ? 0 : (tri[1] == i ? 1 : 2);
      const std::int32_t b = tri[(c + 1) % 3], e = tri[(c + 2) % 3];
      ok = moveKeepsTriangle(ri, nr, s.rest[b], s.rest[e], min_ratio) &&
           moveKeepsTriangle(xi, nx, s.x[b], s.x[e], min_ratio);
    }
    if (ok) break;
    r.backed_off = 1;
    t = attempt == 4 ? T(0) : t * T(0.5);
  }
  s.x[n_idx] = xi + (s.x[j] - xi) * t;
  s.rest[n_idx] = ri + (s.rest[j] - ri) * t;
  s.v[n_idx] = s.v[i];
  s.fixed[n_idx] = s.fixed[i];
  s.k[n_idx] = s.k[i];
  s.tau_f[n_idx] = s.tau_f[i];
  const T mi = s.mass[i];
  const T mn = area_all > T(0) ? mi * (area_move / area_all) : T(0);
  s.mass[n_idx] = mn;
  s.mass[i] = mi - mn;
  return r;
}

// Phase 5: triangle t's vertex that belongs to an accepted particle and lies on its crack side becomes the
// new particle N + rank. Positions of old particles are not changed by phase 4, so the side test repeats
// phase 1's exactly. Replacing a vertex in place keeps the triangle's orientation.
template <typename T>
INC_HD void rebuildTriangle(const SheetView<T>& s, std::int32_t t, const std::uint8_t* accept, const Vec3<T>* dir,
                            const std::int32_t* rank, std::int32_t n_old) {
  std::int32_t* tri = s.tris + 3 * t;
  const Vec3<T> cen = triCentroid(s.x, tri);
  for (int c = 0; c < 3; ++c) {
    const std::int32_t p = tri[c];
    if (p < n_old && accept[p] && onSplitSide(cen, s.x[p], dir[p])) {
      tri[c] = n_old + rank[p];
      return;  // the accepted set is independent: no other vertex of t is accepted
    }
  }
}

}  // namespace inc::tear
