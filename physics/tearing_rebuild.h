// Per-element bodies of the adjacency and PBD constraint rebuild of a torn sheet (per-particle fans, and the older
// sort-based path), shared by the CPU reference and the CUDA kernels.
#pragma once

#include <cstdint>

#include "physics/hd.h"
#include "physics/pbd_constraints.h"
#include "physics/vec3.h"

namespace inc::tear {

// The rebuild sorts packed keys (radix sort on the device, std::stable_sort in the CPU reference). A particle
// index takes `bits` bits (indexBits of the particle count), an edge key 2 * bits: (min << bits) | max, so that
// ascending keys are the host rebuild's (a, b) order with a < b.
INC_HD int indexBits(std::int64_t n) {
  int b = 1;
  while (b < 31 && (std::int64_t(1) << b) <= n) ++b;
  return b;
}

INC_HD std::uint64_t packEdge(std::int32_t a, std::int32_t b, int bits) {
  const std::uint32_t lo = std::uint32_t(a < b ? a : b), hi = std::uint32_t(a < b ? b : a);
  return (std::uint64_t(lo) << bits) | std::uint64_t(hi);
}
INC_HD std::int32_t edgeHigh(std::uint64_t key, int bits) { return std::int32_t(key >> bits); }
INC_HD std::int32_t edgeLow(std::uint64_t key, int bits) {
  return std::int32_t(key & ((std::uint64_t(1) << bits) - 1));
}

// Half-edge h of the triangle list (triangle h / 3, corner h % 3): the edge tri[c] - tri[c+1] and the vertex
// opposite it (the bending wing across this edge).
INC_HD void halfEdge(const std::int32_t* tris, std::int64_t h, int bits, std::uint64_t& key, std::int32_t& opp) {
  const std::int32_t* t = tris + 3 * (h / 3);
  const int c = int(h % 3);
  key = packEdge(t[c], t[(c + 1) % 3], bits);
  opp = t[(c + 2) % 3];
}

// Over sorted half-edge keys: h starts a run of equal keys (a unique edge); its run length is the number of
// triangles on the edge (1 boundary, 2 interior: one bending constraint, > 2 non-manifold: none).
INC_HD bool runHead(const std::uint64_t* keys, std::int64_t h) { return h == 0 || keys[h] != keys[h - 1]; }
INC_HD int runLength(const std::uint64_t* keys, std::int64_t h, std::int64_t total) {
  int m = 1;
  while (h + m < total && keys[h + m] == keys[h]) ++m;
  return m;
}

// First position q in ascending keys[0 .. n) with keys[q] >= v (n when none): CSR offsets from sorted owners.
template <typename K>
INC_HD std::int64_t lowerBound(const K* keys, std::int64_t n, K v) {
  std::int64_t lo = 0, hi = n;
  while (lo < hi) {
    const std::int64_t mid = lo + (hi - lo) / 2;
    if (keys[mid] < v)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}

// Distance constraint e on edge a-b (a < b) and, when c >= 0 and bend_ids is set, bending constraint c with
// wings w0, w1 (written ascending). Rest values from rest positions, exactly as buildTearPbdModel computes them.
// Every rest position is read before the first store: the output pointers may alias `rest` as far as a compiler
// knows, so a store between loads would order the loads behind it (on the device: one more dependent trip to
// L2 per edge in a pass that is as slow as its longest thread).
template <typename T>
INC_HD void writeEdgeConstraint(std::int32_t a, std::int32_t b, std::int32_t w0, std::int32_t w1, std::int64_t e,
                                std::int64_t c, const Vec3<T>* rest, T stretch_compliance, T bending_compliance,
                                std::int32_t* edge_a, std::int32_t* edge_b, std::int32_t* dist_ids, T* dist_rest,
                                T* dist_compliance, std::int32_t* bend_ids, T* bend_rest, T* bend_compliance) {
  const bool bend = c >= 0 && bend_ids;
  const std::int32_t p2 = w0 < w1 ? w0 : w1, p3 = w0 < w1 ? w1 : w0;
  const Vec3<T> ra = rest[a], rb = rest[b];
  Vec3<T> r2, r3;
  if (bend) {
    r2 = rest[p2];
    r3 = rest[p3];
  }
  if (edge_a) edge_a[e] = a;
  if (edge_b) edge_b[e] = b;
  dist_ids[2 * e] = a;
  dist_ids[2 * e + 1] = b;
  dist_rest[e] = norm(ra - rb);
  if (dist_compliance) dist_compliance[e] = stretch_compliance;  // null: the caller fills the constant itself
  if (!bend) return;
  bend_ids[4 * c] = a;
  bend_ids[4 * c + 1] = b;
  bend_ids[4 * c + 2] = p2;
  bend_ids[4 * c + 3] = p3;
  bend_rest[c] = pbd::dihedralAngle(ra, rb, r2, r3);
  if (bend_compliance) bend_compliance[c] = bending_compliance;
}

template <typename T>
INC_HD void writeEdgeConstraints(const std::uint64_t* keys, const std::int32_t* opp, std::int64_t h, int run, int bits,
                                 std::int64_t e, std::int64_t c, const Vec3<T>* rest, T stretch_compliance,
                                 T bending_compliance, std::int32_t* edge_a, std::int32_t* edge_b,
                                 std::int32_t* dist_ids, T* dist_rest, T* dist_compliance, std::int32_t* bend_ids,
                                 T* bend_rest, T* bend_compliance) {
  const std::int32_t a = edgeHigh(keys[h], bits), b = edgeLow(keys[h], bits);
  writeEdgeConstraint<T>(a, b, run == 2 ? opp[h] : -1, run == 2 ? opp[h + 1] : -1, e, run == 2 ? c : -1, rest,
                         stretch_compliance, bending_compliance, edge_a, edge_b, dist_ids, dist_rest, dist_compliance,
                         bend_ids, bend_rest, bend_compliance);
}

// Jacobi scale of constraint c of a fixed-arity block: 1 / (this block's constraints on its busiest movable
// participant), at least 1 constraint (finalizePbdModel's rule; w == 0 marks a fixed particle).
template <typename T>
INC_HD T jacobiScaleOf(const std::int32_t* ids, int arity, std::int64_t c, const std::int32_t* particle_offsets,
                       const T* inv_mass) {
  int busiest = 1;
  for (int k = 0; k < arity; ++k) {
    const std::int32_t p = ids[arity * c + k];
    if (!(inv_mass[p] > T(0))) continue;
    const int deg = particle_offsets[p + 1] - particle_offsets[p];
    busiest = deg > busiest ? deg : busiest;
  }
  return T(1) / T(busiest);
}

// ----------------------------------------------------------------------------------------------
// Per-particle rebuild (no global sort; docs/tearing.md, "Device-resident path"). Every quantity of particle p
// is derived from p's fan (its triangles) and, for edges, from the fan of the edge's lower particle; rows are
// written unsorted into their exact-sized final segments and then sorted in place, so no step needs a local
// buffer of bounded capacity (a large fan costs O(fan^2) work, never a truncation). Preconditions: every
// triangle has three distinct vertices and no two triangles have the same vertex set (checkTearMesh's
// degenerate == 0 and duplicates == 0, which the tearing step keeps); the arrays then equal, one for one,
// TearSheet::rebuildTopology() + buildTearPbdModel(coloring = false).

// Ascending insertion sort of a short row in place (a particle's triangles, partners or slots).
INC_HD void sortRow(std::int32_t* a, int n) {
  for (int i = 1; i < n; ++i) {
    const std::int32_t v = a[i];
    int j = i - 1;
    while (j >= 0 && a[j] > v) {
      a[j + 1] = a[j];
      --j;
    }
    a[j + 1] = v;
  }
}

// Ascending bitonic sorting network over kNetworkRow values. Unrolled, every index is a constant, so on the device
// the array stays in registers: no memory access at all, where an insertion sort waits on a load per step.
constexpr int kNetworkRow = 16;

INC_HD void sortNetwork(std::int32_t (&v)[kNetworkRow]) {
  INC_UNROLL
  for (int ks = 1; ks <= 4; ++ks) {  // merge blocks of k = 2^ks (kNetworkRow = 2^4)
    INC_UNROLL
    for (int js = ks - 1; js >= 0; --js) {  // compare partners j = 2^js apart
      INC_UNROLL
      for (int i = 0; i < kNetworkRow; ++i) {
        const int l = i ^ (1 << js);
        if (l <= i) continue;
        const bool ascending = (i & (1 << ks)) == 0;
        const std::int32_t a = v[i], b = v[l];
        const bool swap = ascending ? a > b : a < b;
        v[i] = swap ? b : a;
        v[l] = swap ? a : b;
      }
    }
  }
}

// Rows of up to kLocalRow entries are built and sorted in a per-thread array and written once: on the device
// that array is local memory, which L1 keeps, where sorting in place costs a dependent global load and store
// per insertion step (the per-particle passes are one wave of threads, each as slow as its longest chain of
// dependent loads); rows of up to kNetworkRow entries (a lattice vertex's triangles, bending slots and partners)
// are sorted in registers by the network. Longer rows are handled in place. All give the same ascending row.
constexpr int kLocalRow = 32;

// A row already in a per-thread array (or one too long for it): the network up to kNetworkRow, else in place.
INC_HD void sortShortRow(std::int32_t* a, int n) {
  if (n > kNetworkRow) {
    sortRow(a, n);
    return;
  }
  std::int32_t v[kNetworkRow];
  INC_UNROLL
  for (int i = 0; i < kNetworkRow; ++i) v[i] = i < n ? a[i] : INT32_MAX;  // the padding sorts last
  sortNetwork(v);
  INC_UNROLL
  for (int i = 0; i < kNetworkRow; ++i)
    if (i < n) a[i] = v[i];
}

// A row in global memory.
INC_HD void sortRowLocal(std::int32_t* a, int n) {
  if (n <= kNetworkRow || n > kLocalRow) {
    sortShortRow(a, n);
    return;
  }
  std::int32_t t[kLocalRow];
  for (int i = 0; i < n; ++i) t[i] = a[i];
  sortRow(t, n);
  for (int i = 0; i < n; ++i) a[i] = t[i];
}

// The particle -> triangles CSR (rows ascending once sorted) over the triangle list.
struct Fan {
  const std::int32_t* tris = nullptr;        // 3 per triangle
  const std::int32_t* pt_offsets = nullptr;  // n + 1
  const std::int32_t* pt_tris = nullptr;
};

// Particle p's fan read from the global arrays: the general path, for fans too large for FanPairs (and for the
// tests, which force it to check that both paths give the same rows).
struct FanRow {
  const Fan* fan;
  std::int32_t p;
  int count;  // triangles
  INC_HD FanRow(const Fan& f, std::int32_t p_) : fan(&f), p(p_), count(f.pt_offsets[p_ + 1] - f.pt_offsets[p_]) {}
  INC_HD const std::int32_t* triangle(int q) const { return fan->tris + 3 * fan->pt_tris[fan->pt_offsets[p] + q]; }
  // Corner k: vertex k % 3 of the (k / 3)-th triangle (p itself is one of each triangle's three).
  INC_HD std::int32_t corner(int k) const { return triangle(k / 3)[k % 3]; }
  INC_HD int corners() const { return 3 * count; }
};

// The fast path for fans of up to kFanPairs triangles (a lattice vertex has 6, a split one fewer): the two other
// vertices of each triangle, 2 kFanPairs values in registers (every loop over them is unrolled, so no index is
// dynamic and nothing goes to local memory), padded with INT32_MAX. Sorted by the register network they give p's
// partners (the distinct values), and a value's run length is the number of p's triangles on that edge (two: a
// bending constraint, whose wings are the values paired with it). On the device this replaced corner-by-corner
// duplicate searches over a per-thread copy in local memory: those passes issued ~10k instructions per warp.
constexpr int kFanPairs = kNetworkRow / 2;

struct FanPairs {
  std::int32_t o[kNetworkRow];  // (u, w) of triangle q at 2 q, 2 q + 1

  // False (nothing loaded) when p has more than min(cache, kFanPairs) triangles.
  INC_HD bool load(const Fan& f, std::int32_t p, int cache) {
    const std::int32_t b = f.pt_offsets[p];
    const int count = f.pt_offsets[p + 1] - b;
    if (count > cache || count > kFanPairs) return false;
    INC_UNROLL
    for (int q = 0; q < kFanPairs; ++q) {
      std::int32_t u = INT32_MAX, w = INT32_MAX;
      if (q < count) {
        const std::int32_t* t = f.tris + 3 * f.pt_tris[b + q];
        const std::int32_t t0 = t[0], t1 = t[1], t2 = t[2];
        u = t0 == p ? t1 : (t1 == p ? t2 : t0);
        w = t0 == p ? t2 : (t1 == p ? t0 : t1);
      }
      o[2 * q] = u;
      o[2 * q + 1] = w;
    }
    return true;
  }

  // The wings of edge p-b: true when exactly two of p's triangles contain b (bendingWings' rule).
  INC_HD bool wings(std::int32_t b, std::int32_t& p2, std::int32_t& p3) const {
    int found = 0;
    std::int32_t w0 = -1, w1 = -1;
    INC_UNROLL
    for (int q = 0; q < kFanPairs; ++q) {
      const std::int32_t u = o[2 * q], w = o[2 * q + 1];
      if (u != b && w != b) continue;
      const std::int32_t wing = u == b ? w : u;
      if (found == 0) w0 = wing;
      if (found == 1) w1 = wing;
      ++found;
    }
    if (found != 2) return false;
    p2 = w0 < w1 ? w0 : w1;
    p3 = w0 < w1 ? w1 : w0;
    return true;
  }

  // The values sorted ascending (padding last).
  INC_HD void sorted(std::int32_t (&s)[kNetworkRow]) const {
    INC_UNROLL
    for (int i = 0; i < kNetworkRow; ++i) s[i] = o[i];
    sortNetwork(s);
  }
};

// In sorted pair values s: whether s[i] starts a run (a distinct partner), and whether that run has length 2.
INC_HD bool pairRunHead(const std::int32_t (&s)[kNetworkRow], int i) {
  return s[i] != INT32_MAX && (i == 0 || s[i - 1] != s[i]);
}
INC_HD bool pairRunOfTwo(const std::int32_t (&s)[kNetworkRow], int i) {
  return i + 1 < kNetworkRow && s[i + 1] == s[i] && !(i + 2 < kNetworkRow && s[i + 2] == s[i]);
}

// Whether corner k's vertex v already occurred among corners [0, k) of the fan (the first occurrence counts).
INC_HD bool seenInFan(const FanRow& r, int k, std::int32_t v) {
  for (int j = 0; j < k; ++j)
    if (r.corner(j) == v) return true;
  return false;
}

// Edge a-b (a < b, a = r.p) gets a bending constraint: exactly two of a's triangles contain b, and each has a
// vertex that is neither a nor b (the wings, returned ascending). buildTearPbdModel's merge of the two
// particles' triangle lists visits the same triangles in the same (ascending) order.
INC_HD bool bendingWings(const FanRow& r, std::int32_t b, std::int32_t& p2, std::int32_t& p3) {
  const std::int32_t a = r.p;
  int found = 0;
  std::int32_t w[2] = {-1, -1};
  for (int q = 0; q < r.count; ++q) {
    const std::int32_t* t = r.triangle(q);
    if (t[0] != b && t[1] != b && t[2] != b) continue;
    std::int32_t o = -1;
    for (int c = 0; c < 3; ++c)
      if (t[c] != a && t[c] != b) o = t[c];
    if (found < 2) w[found] = o;
    ++found;
  }
  if (found != 2 || w[0] < 0 || w[1] < 0) return false;
  p2 = w[0] < w[1] ? w[0] : w[1];
  p3 = w[0] < w[1] ? w[1] : w[0];
  return true;
}
// Per-particle counts; their exclusive scan numbers everything: partners (pe_offsets, and the distance block's
// particle -> slot offsets, since a particle's distance slots are its bonds), upper partners (edges (p, b),
// b > p: the edge numbers in (a, b) order) and bending constraints on those edges (bending numbers in edge
// order). The bending block's particle -> slot offsets are counted from its constraints once they exist (see
// FanOutputs::bend_particle_offsets): a particle's wing slots would need the fans of its opposite edges' ends.
struct FanCounts {
  std::int32_t partners = 0, upper = 0, bend_upper = 0;
};
struct AddFanCounts {
  INC_HD FanCounts operator()(const FanCounts& x, const FanCounts& y) const {
    FanCounts r;
    r.partners = x.partners + y.partners;
    r.upper = x.upper + y.upper;
    r.bend_upper = x.bend_upper + y.bend_upper;
    return r;
  }
};

// p's partners are the distinct other vertices of its triangles (an edge joins every two vertices of a
// triangle, so this is rebuildTopology's pe row: partners below p, then above, both ascending); its upper edges
// (p, v), v > p, and those of them with a bending constraint (bendingWings over p's own fan, which holds both
// triangles of the edge).
// fan_cache: the most triangles FanPairs takes (tests pass 0 to force FanRow's global reads); the counts never
// depend on it.
INC_HD FanCounts fanCounts(const Fan& f, std::int32_t p, int fan_cache = kFanPairs) {
  FanCounts r;
  FanPairs fp;
  if (fp.load(f, p, fan_cache)) {
    std::int32_t s[kNetworkRow];
    fp.sorted(s);
    INC_UNROLL
    for (int i = 0; i < kNetworkRow; ++i) {
      if (!pairRunHead(s, i)) continue;
      ++r.partners;
      if (s[i] > p) {
        ++r.upper;
        r.bend_upper += pairRunOfTwo(s, i) ? 1 : 0;
      }
    }
    return r;
  }
  const FanRow row(f, p);
  const int m = row.corners();
  std::int32_t p2 = 0, p3 = 0;
  for (int k = 0; k < m; ++k) {
    const std::int32_t v = row.corner(k);
    if (v == p || seenInFan(row, k, v)) continue;
    ++r.partners;
    if (v > p) {
      ++r.upper;
      r.bend_upper += bendingWings(row, v, p2, p3) ? 1 : 0;
    }
  }
  return r;
}

// Where the per-particle rebuild writes (device or host pointers). off: the exclusive scan of fanCounts over
// n + 1 entries (entry n the totals). bend_ids == nullptr: no bending block (bending outputs unused).
template <typename T>
struct FanOutputs {
  const FanCounts* off = nullptr;
  const Vec3<T>* rest = nullptr;  // m
  T stretch_compliance = T(0), bending_compliance = T(0);
  std::int32_t* pe_offsets = nullptr;  // n + 1
  std::int32_t* pe_partner = nullptr;  // off[n].partners
  std::int32_t* edge_a = nullptr;      // optional: off[n].upper each
  std::int32_t* edge_b = nullptr;
  std::int32_t* dist_ids = nullptr;
  T* dist_rest = nullptr;
  T* dist_compliance = nullptr;
  std::int32_t* dist_particle_offsets = nullptr;  // n + 1
  std::int32_t* dist_particle_slots = nullptr;    // 2 per edge
  std::int32_t* bend_ids = nullptr;
  T* bend_rest = nullptr;
  T* bend_compliance = nullptr;
  // The bending block's particle -> slot CSR is not written per particle: slot s belongs to particle bend_ids[s],
  // so a backend counts, scans and places the slots after writeFanEdges and sorts each row ascending (the order of
  // rebuildTopology + buildTearPbdModel).
  std::int32_t* bend_particle_offsets = nullptr;  // n + 1
  std::int32_t* bend_particle_slots = nullptr;    // 4 per bending constraint
  // writeFanEdges stores partner-indexed element k (pe_partner, dist_particle_slots) at k - partner_base, edge e
  // at e - edge_base and bending constraint c at c - bend_base (the values stay global numbers): 0 for the whole
  // arrays; a device block staging its particles' contiguous ranges in shared memory sets its first indices.
  std::int64_t partner_base = 0, edge_base = 0, bend_base = 0;
};

// Offsets of particle p = 0 .. n (p == n: the totals) into the CSR arrays.
template <typename T>
INC_HD void writeFanOffsets(const FanOutputs<T>& o, std::int32_t p) {
  const FanCounts& b = o.off[p];
  if (o.pe_offsets) o.pe_offsets[p] = b.partners;
  if (o.dist_particle_offsets) o.dist_particle_offsets[p] = b.partners;
}

// Pass 2 for particle p < n: its partner row (ascending), its upper edges (p, b) as distance constraints (and
// bending constraints where the edge has two triangles), their number of bending constraint, and p's own
// distance slots 2 e of those edges (the upper part of its distance row; the lower part needs the partners'
// rows: writeLowerDistanceSlot).
template <typename T>
INC_HD void writeFanEdges(const Fan& f, const FanOutputs<T>& o, std::int32_t p, int fan_cache = kFanPairs) {
  const FanCounts &b = o.off[p], &e = o.off[p + 1];
  std::int32_t* const out_row = o.pe_partner + (b.partners - o.partner_base);
  const int np = e.partners - b.partners, nup = e.upper - b.upper, nlow = np - nup;
  FanPairs fp;
  const bool pairs = fp.load(f, p, fan_cache);
  if (pairs) {
    std::int32_t s[kNetworkRow];
    fp.sorted(s);
    int w = 0;
    INC_UNROLL
    for (int i = 0; i < kNetworkRow; ++i)
      if (pairRunHead(s, i)) out_row[w++] = s[i];
  } else {
    const FanRow fr(f, p);
    const int m = fr.corners();
    std::int32_t local[kLocalRow];
    std::int32_t* row = np <= kLocalRow ? local : out_row;
    int w = 0;
    for (int k = 0; k < m && w < np; ++k) {  // w < np: fanCounts counted exactly these, so this never cuts
      const std::int32_t v = fr.corner(k);
      if (v == p) continue;
      bool dup = false;
      for (int j = 0; j < w && !dup; ++j) dup = row[j] == v;
      if (!dup) row[w++] = v;
    }
    sortShortRow(row, w);
    if (row == local)
      for (int j = 0; j < w; ++j) out_row[j] = local[j];
  }
  std::int32_t c = b.bend_upper;
  for (int k = 0; k < nup; ++k) {
    const std::int32_t q = out_row[nlow + k], edge = b.upper + k;
    std::int32_t p2 = -1, p3 = -1;
    const bool bend = pairs ? fp.wings(q, p2, p3) : bendingWings(FanRow(f, p), q, p2, p3);
    writeEdgeConstraint<T>(p, q, p2, p3, edge - o.edge_base, bend ? c - o.bend_base : -1, o.rest, o.stretch_compliance,
                           o.bending_compliance, o.edge_a, o.edge_b, o.dist_ids, o.dist_rest, o.dist_compliance,
                           o.bend_ids, o.bend_rest, o.bend_compliance);
    c += bend ? 1 : 0;
    o.dist_particle_slots[b.partners - o.partner_base + nlow + k] = 2 * edge;
  }
}

// Pass 3 for edge e = (a, b), a < b (after writeFanEdges of every particle): slot 2 e + 1 in b's distance row.
// The row's lower part lists b's partners below b ascending, and b's edges from below are numbered in the same
// order (by their lower end), so the slot's place is a's rank there: one search in b's own row.
template <typename T>
INC_HD void writeLowerDistanceSlot(const FanOutputs<T>& o, std::int64_t e) {
  const std::int32_t a = o.dist_ids[2 * e], b = o.dist_ids[2 * e + 1];
  const FanCounts &s = o.off[b], &t = o.off[b + 1];
  const std::int32_t nlow = (t.partners - s.partners) - (t.upper - s.upper);
  const std::int64_t k = lowerBound<std::int32_t>(o.pe_partner + s.partners, nlow, a);
  o.dist_particle_slots[s.partners + k] = std::int32_t(2 * e + 1);
}

}  // namespace inc::tear
