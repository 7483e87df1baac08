// Tearable sheet: builders, adjacency rebuild (counting sorts), PBD model assembly, removal tools, validity checks.
#include "model/tearing_sheet.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <parallel/algorithm>

#include "base/parallel.h"
#include "model/input_error.h"
#include "physics/pbd_constraints.h"
#include "physics/tearing_tresca.h"

namespace inc {

const char* tearCriterionName(TearCriterion c) {
  switch (c) {
    case TearCriterion::Threshold: return "traditional";
    case TearCriterion::TrescaBonds: return "tresca";
    case TearCriterion::TrescaPrincipal: return "tresca_principal";
  }
  return "?";
}

TearCriterion parseTearCriterion(const std::string& text, const std::string& file, const std::string& key) {
  if (text == "traditional" || text == "threshold") return TearCriterion::Threshold;
  if (text == "tresca") return TearCriterion::TrescaBonds;
  if (text == "tresca_principal") return TearCriterion::TrescaPrincipal;
  throw InputError(file, key, "unknown tearing criterion '" + text + "' (traditional, tresca, tresca_principal)");
}

namespace {

std::uint64_t edgeKey(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

// CSR from (owner, value) pairs, values ascending within an owner when pairs are pushed in ascending order.
void buildCsr(std::size_t n, const std::vector<std::int32_t>& owner, const std::vector<std::int32_t>& value,
              std::vector<std::int32_t>& offsets, std::vector<std::int32_t>& out) {
  offsets.assign(n + 1, 0);
  for (std::int32_t o : owner) ++offsets[o + 1];
  for (std::size_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
  out.resize(owner.size());
  std::vector<std::int32_t> fill(offsets.begin(), offsets.end() - 1);
  for (std::size_t k = 0; k < owner.size(); ++k) out[fill[owner[k]]++] = value[k];
}

template <typename T>
T restArea(const TearSheet<T>& s, std::size_t t) {
  const auto& tr = s.tris[t];
  return norm(tear::triangleAreaVector(s.rest[tr[0]], s.rest[tr[1]], s.rest[tr[2]]));
}

}  // namespace

template <typename T>
void TearSheet<T>::rebuildTopology() {
  const std::size_t n = x.size();
  // particle -> triangles, ascending (counting sort over corners in triangle order).
  std::vector<std::int32_t> own, val;
  own.reserve(tris.size() * 3);
  val.reserve(tris.size() * 3);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      own.push_back(tris[t][c]);
      val.push_back(std::int32_t(t));
    }
  buildCsr(n, own, val, pt_offsets, pt_tris);
  // Unique bonds sorted by (a, b), a < b, without a global sort: particle a lists its larger neighbours over
  // its own triangles (sorted, unique; a handful), counts them, and after a prefix sum writes them in place.
  std::vector<std::int32_t> count(n + 1, 0);
  auto upper = [&](std::size_t a, std::int32_t* buf, int cap) {
    int m = 0;
    for (std::int32_t q = pt_offsets[a]; q < pt_offsets[a + 1]; ++q)
      for (int c = 0; c < 3; ++c) {
        const std::int32_t b = tris[pt_tris[q]][c];
        if (b > std::int32_t(a) && m < cap) buf[m++] = b;
      }
    std::sort(buf, buf + m);
    return int(std::unique(buf, buf + m) - buf);
  };
  int max_ring = 0;
  for (std::size_t a = 0; a < n; ++a) max_ring = std::max(max_ring, 2 * (pt_offsets[a + 1] - pt_offsets[a]));
  cpu::parallelFor(std::int64_t(n), [&](std::int64_t a) {
    thread_local std::vector<std::int32_t> buf;
    buf.resize(std::size_t(max_ring) + 1);
    count[a + 1] = upper(std::size_t(a), buf.data(), max_ring);
  });
  for (std::size_t a = 0; a < n; ++a) count[a + 1] += count[a];
  const std::size_t ne = std::size_t(count[n]);
  edge_a.resize(ne);
  edge_b.resize(ne);
  cpu::parallelFor(std::int64_t(n), [&](std::int64_t a) {
    thread_local std::vector<std::int32_t> buf;
    buf.resize(std::size_t(max_ring) + 1);
    const int m = upper(std::size_t(a), buf.data(), max_ring);
    for (int k = 0; k < m; ++k) {
      edge_a[count[a] + k] = std::int32_t(a);
      edge_b[count[a] + k] = buf[k];
    }
  });
  // particle -> partners, ascending. Edges are sorted by (a, b); the counting sort in buildCsr keeps push
  // order per owner, so pushing every (b <- a) first and then every (a <- b) lists, for each particle p, its
  // partners below p ascending and then those above p ascending.
  own.clear();
  val.clear();
  for (std::size_t e = 0; e < ne; ++e) {
    own.push_back(edge_b[e]);
    val.push_back(edge_a[e]);
  }
  for (std::size_t e = 0; e < ne; ++e) {
    own.push_back(edge_a[e]);
    val.push_back(edge_b[e]);
  }
  buildCsr(n, own, val, pe_offsets, pe_partner);
}

// Two triangles of the quad a-b-c-d (counter-clockwise), split along a-c or b-d; alternating the diagonal
// keeps the lattice free of a preferred tearing direction.
template <typename T>
void pushQuad(TearSheet<T>& s, std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d, bool diagonal_ac) {
  if (diagonal_ac) {
    s.tris.push_back({a, b, c});
    s.tris.push_back({a, c, d});
  } else {
    s.tris.push_back({a, b, d});
    s.tris.push_back({b, c, d});
  }
}

// State at rest, uniform material, lumped masses (a third of each triangle's areal mass per corner),
// reference normals, and the bond/bending topology.
template <typename T>
void finishSheet(TearSheet<T>& s, double rho_a, double k_pa, double tau_f_pa) {
  const std::size_t n = s.rest.size();
  s.x = s.rest;
  s.v.assign(n, Vec3<T>());
  s.mass.assign(n, T(0));
  s.fixed.assign(n, 0);
  s.k.assign(n, T(k_pa));
  s.tau_f.assign(n, T(tau_f_pa));
  for (std::size_t t = 0; t < s.tris.size(); ++t) {
    const auto& tr = s.tris[t];
    const Vec3<T> av = tear::triangleAreaVector(s.rest[tr[0]], s.rest[tr[1]], s.rest[tr[2]]);
    s.ref_normal.push_back(av * (T(1) / norm(av)));
    for (int c = 0; c < 3; ++c) s.mass[tr[c]] += T(rho_a) * norm(av) / T(3);
  }
  s.rebuildTopology();
}

template <typename T>
TearSheet<T> makeTearGrid(int nx, int ny, double h, double rho_a, const Vec3d& origin, double k_pa, double tau_f_pa) {
  const char* f = "tear grid";
  if (nx < 2 || ny < 2) throw InputError(f, "size", "need at least 2 x 2 particles");
  if (!(h > 0) || !(rho_a > 0)) throw InputError(f, "spacing", "spacing and area density must be > 0");
  if (!(k_pa > 0) || !(tau_f_pa > 0)) throw InputError(f, "material", "k and tau_f must be > 0");
  TearSheet<T> s;
  auto id = [&](int i, int j) { return std::int32_t(j * nx + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) s.rest.push_back(Vec3<T>(origin + Vec3d(i * h, j * h, 0.0)));
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const std::int32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      pushQuad(s, a, b, c, d, (i + j) % 2 == 0);
    }
  finishSheet(s, rho_a, k_pa, tau_f_pa);
  return s;
}

template <typename T>
TearSheet<T> makeTearTube(int n_around, int n_along, double radius, double length, double rho_a, double k_pa,
                          double tau_f_pa) {
  const char* f = "tear tube";
  if (n_around < 3 || n_along < 2) throw InputError(f, "size", "need at least 3 x 2 particles");
  if (!(radius > 0) || !(length > 0) || !(rho_a > 0)) throw InputError(f, "geometry", "must be > 0");
  if (!(k_pa > 0) || !(tau_f_pa > 0)) throw InputError(f, "material", "k and tau_f must be > 0");
  TearSheet<T> s;
  const double two_pi = 6.283185307179586;
  auto id = [&](int i, int j) { return std::int32_t(j * n_around + (i % n_around)); };
  for (int j = 0; j < n_along; ++j)
    for (int i = 0; i < n_around; ++i) {
      const double a = two_pi * i / n_around;
      s.rest.push_back(Vec3<T>(Vec3d(radius * std::cos(a), radius * std::sin(a), length * j / (n_along - 1))));
    }
  for (int j = 0; j + 1 < n_along; ++j)
    for (int i = 0; i < n_around; ++i) {
      // around = +theta, along = +z: (theta, z) counter-clockwise seen from outside gives outward normals.
      const std::int32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      pushQuad(s, a, b, c, d, (i + j) % 2 == 0);
    }
  finishSheet(s, rho_a, k_pa, tau_f_pa);
  return s;
}

namespace {
bool inBox(const Vec3d& p, const Vec3d& lo, const Vec3d& hi) {
  return p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y && p.z <= hi.z;
}
}  // namespace

template <typename T>
void applyTearRegions(TearSheet<T>& s, const std::vector<TearRegion>& regions) {
  for (std::size_t r = 0; r < regions.size(); ++r)
    if (!(regions[r].k_pa > 0) || !(regions[r].tau_f_pa > 0))
      throw InputError("tearing", "regions[" + std::to_string(r) + "]", "k and tau_f must be > 0");
  for (std::size_t i = 0; i < s.size(); ++i)
    for (const auto& r : regions)
      if (inBox(Vec3d(s.rest[i]), r.min, r.max)) {
        s.k[i] = T(r.k_pa);
        s.tau_f[i] = T(r.tau_f_pa);
      }
}

template <typename T>
void fixTearParticles(TearSheet<T>& s, const Vec3d& lo, const Vec3d& hi) {
  for (std::size_t i = 0; i < s.size(); ++i)
    if (inBox(Vec3d(s.rest[i]), lo, hi)) s.fixed[i] = 1;
}

template <typename T>
PbdModel<T> buildTearPbdModel(const TearSheet<T>& s, const TearModelOptions& opt) {
  if (opt.stretch_compliance < 0 || opt.bending_compliance < 0)
    throw InputError("tearing", "compliance", "must be >= 0");
  const std::size_t n = s.size();
  PbdModel<T> m;
  m.rest_positions = s.rest;
  m.masses = s.mass;
  m.inv_mass.resize(n);
  for (std::size_t i = 0; i < n; ++i) m.inv_mass[i] = s.fixed[i] ? T(0) : T(1) / s.mass[i];
  m.rest_radii.assign(n, T(0));
  PbdConstraintBlock<T> dist, bend;
  dist.kind = PbdConstraintKind::Distance;
  bend.kind = PbdConstraintKind::Bending;
  dist.stiffness = bend.stiffness = T(opt.pbd_stiffness);
  const std::size_t ne = s.edge_a.size();
  dist.ids.resize(2 * ne);
  dist.offsets.resize(ne + 1);
  dist.rest.resize(ne);
  dist.compliance.assign(ne, T(opt.stretch_compliance));
  dist.offsets[0] = 0;
  cpu::parallelFor(std::int64_t(ne), [&](std::int64_t e) {
    dist.ids[2 * e] = s.edge_a[e];
    dist.ids[2 * e + 1] = s.edge_b[e];
    dist.offsets[e + 1] = std::int32_t(2 * e + 2);
    dist.rest[e] = norm(s.rest[s.edge_a[e]] - s.rest[s.edge_b[e]]);
  });
  // Interior edges: an edge (a, b) whose particles share exactly two triangles gets one bending constraint,
  // wings (the opposite vertices) ascending, in edge order. The shared triangles come from merging the sorted
  // particle -> triangle lists of a and b (no sort of all half-edges); count, prefix sum, fill in parallel.
  if (s.pt_offsets.size() != n + 1 || s.pe_offsets.size() != n + 1)
    throw InputError("tearing", "topology", "the sheet's adjacency is stale: call rebuildTopology() first");
  std::vector<std::int32_t> wings(2 * ne, -1);
  std::vector<std::int32_t> has(ne + 1, 0);
  cpu::parallelFor(std::int64_t(ne), [&](std::int64_t e) {
    const std::int32_t a = s.edge_a[e], b = s.edge_b[e];
    std::int32_t ia = s.pt_offsets[a], ib = s.pt_offsets[b], found = 0, w[2] = {-1, -1};
    const std::int32_t ea = s.pt_offsets[a + 1], eb = s.pt_offsets[b + 1];
    while (ia < ea && ib < eb) {
      const std::int32_t ta = s.pt_tris[ia], tb = s.pt_tris[ib];
      if (ta < tb) {
        ++ia;
        continue;
      }
      if (tb < ta) {
        ++ib;
        continue;
      }
      const auto& tr = s.tris[ta];
      std::int32_t o = -1;
      for (int c = 0; c < 3; ++c)
        if (tr[c] != a && tr[c] != b) o = tr[c];
      if (found < 2) w[found] = o;
      ++found;
      ++ia;
      ++ib;
    }
    if (found == 2 && w[0] >= 0 && w[1] >= 0) {
      wings[2 * e] = std::min(w[0], w[1]);
      wings[2 * e + 1] = std::max(w[0], w[1]);
      has[e + 1] = 1;
    }
  });
  for (std::size_t e = 0; e < ne; ++e) has[e + 1] += has[e];
  const std::size_t nb = std::size_t(has[ne]);
  bend.ids.resize(4 * nb);
  bend.offsets.resize(nb + 1);
  bend.offsets[0] = 0;
  bend.rest.resize(nb);
  bend.compliance.assign(nb, T(opt.bending_compliance));
  cpu::parallelFor(std::int64_t(ne), [&](std::int64_t e) {
    if (has[e + 1] == has[e]) return;
    const std::size_t c = std::size_t(has[e]);
    const std::int32_t a = s.edge_a[e], b = s.edge_b[e], p2 = wings[2 * e], p3 = wings[2 * e + 1];
    bend.ids[4 * c] = a;
    bend.ids[4 * c + 1] = b;
    bend.ids[4 * c + 2] = p2;
    bend.ids[4 * c + 3] = p3;
    bend.offsets[c + 1] = std::int32_t(4 * c + 4);
    bend.rest[c] = pbd::dihedralAngle(s.rest[a], s.rest[b], s.rest[p2], s.rest[p3]);
  });
  m.blocks.push_back(std::move(dist));
  if (bend.count() > 0) m.blocks.push_back(std::move(bend));
  m.overlap_offsets.assign(n + 1, 0);
  if (opt.coloring) {
    finalizePbdModel(m);
    return m;
  }
  // finalizePbdModel's derived data without the colouring (valid by construction: ids from the mesh).
  for (PbdConstraintBlock<T>& b : m.blocks) {
    fillParticleSlots(b, n);
    b.jacobi_scale.assign(b.ids.size(), T(1));
    cpu::parallelFor(std::int64_t(b.count()), [&](std::int64_t c) {
      int busiest = 1;
      for (std::int32_t q = b.offsets[c]; q < b.offsets[c + 1]; ++q) {
        const std::int32_t p = b.ids[q];
        if (s.fixed[p]) continue;
        busiest = std::max(busiest, b.particle_offsets[p + 1] - b.particle_offsets[p]);
      }
      for (std::int32_t q = b.offsets[c]; q < b.offsets[c + 1]; ++q) b.jacobi_scale[q] = T(1) / T(busiest);
    });
    b.coloring = ConstraintColoring{};
  }
  return m;
}

template <typename T>
TearMeshCheck checkTearMesh(const TearSheet<T>& s) {
  TearMeshCheck r;
  const std::size_t n = s.size();
  double mean_area = 0;
  for (std::size_t t = 0; t < s.tris.size(); ++t) mean_area += double(restArea(s, t));
  mean_area /= std::max<std::size_t>(1, s.tris.size());
  std::vector<int> used(n, 0);
  std::vector<std::array<std::int32_t, 3>> sorted;
  std::vector<std::pair<std::uint64_t, int>> dir_edges;  // key, +1 if traversed a->b with a<b else -1
  for (std::size_t t = 0; t < s.tris.size(); ++t) {
    const auto& tr = s.tris[t];
    bool bad = false;
    for (int c = 0; c < 3; ++c)
      if (tr[c] < 0 || std::size_t(tr[c]) >= n) bad = true;
    if (bad) {
      ++r.dead_refs;
      continue;
    }
    for (int c = 0; c < 3; ++c) used[tr[c]] = 1;
    if (tr[0] == tr[1] || tr[1] == tr[2] || tr[0] == tr[2] || double(restArea(s, t)) < 1e-6 * mean_area) ++r.degenerate;
    const Vec3<T> ar = tear::triangleAreaVector(s.rest[tr[0]], s.rest[tr[1]], s.rest[tr[2]]);
    const Vec3<T> ac = tear::triangleAreaVector(s.x[tr[0]], s.x[tr[1]], s.x[tr[2]]);
    if (!(dot(ar, s.ref_normal[t]) > T(0))) ++r.inverted;
    if (!(dot(ac, s.ref_normal[t]) > T(0))) ++r.inverted_current;
    std::array<std::int32_t, 3> so = tr;
    std::sort(so.begin(), so.end());
    sorted.push_back(so);
    for (int c = 0; c < 3; ++c) {
      const std::int32_t a = tr[c], b = tr[(c + 1) % 3];
      dir_edges.push_back({edgeKey(a, b), a < b ? 1 : -1});
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    if (!used[i]) ++r.dead_refs;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t k = 1; k < sorted.size(); ++k)
    if (sorted[k] == sorted[k - 1]) ++r.duplicates;
  std::sort(dir_edges.begin(), dir_edges.end());
  for (std::size_t h = 0; h < dir_edges.size();) {
    std::size_t e = h;
    int sum = 0;
    while (e < dir_edges.size() && dir_edges[e].first == dir_edges[h].first) sum += dir_edges[e++].second;
    if (e - h > 2) ++r.non_manifold_edges;
    if (e - h == 2 && sum != 0) ++r.inconsistent_edges;
    h = e;
  }
  return r;
}

template <typename T>
double tearBoundaryLength(const TearSheet<T>& s, bool rest_config) {
  std::vector<std::uint64_t> keys;
  for (const auto& t : s.tris)
    for (int c = 0; c < 3; ++c) keys.push_back(edgeKey(t[c], t[(c + 1) % 3]));
  std::sort(keys.begin(), keys.end());
  const std::vector<Vec3<T>>& p = rest_config ? s.rest : s.x;
  double len = 0;
  for (std::size_t h = 0; h < keys.size();) {
    std::size_t e = h;
    while (e < keys.size() && keys[e] == keys[h]) ++e;
    if (e - h == 1) len += double(norm(p[keys[h] >> 32] - p[keys[h] & 0xffffffffu]));
    h = e;
  }
  return len;
}

template <typename T>
double totalMass(const TearSheet<T>& s) {
  double m = 0;
  for (T v : s.mass) m += double(v);
  return m;
}

template <typename T>
Vec3d totalMomentum(const TearSheet<T>& s) {
  Vec3d p;
  for (std::size_t i = 0; i < s.size(); ++i) p += Vec3d(s.v[i]) * double(s.mass[i]);
  return p;
}

template <typename T>
std::vector<std::uint8_t> markInBox(const TearSheet<T>& s, const Vec3d& lo, const Vec3d& hi) {
  std::vector<std::uint8_t> m(s.size(), 0);
  for (std::size_t i = 0; i < s.size(); ++i) m[i] = inBox(Vec3d(s.rest[i]), lo, hi) ? 1 : 0;
  return m;
}

template <typename T>
std::vector<std::uint8_t> markNearSegment(const TearSheet<T>& s, const Vec3d& a, const Vec3d& b, double radius) {
  std::vector<std::uint8_t> m(s.size(), 0);
  const Vec3d ab = b - a;
  const double l2 = norm2(ab);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const Vec3d p(s.x[i]);
    double t = l2 > 0 ? dot(p - a, ab) / l2 : 0.0;
    t = std::min(1.0, std::max(0.0, t));
    m[i] = norm(p - (a + ab * t)) <= radius ? 1 : 0;
  }
  return m;
}

template <typename T>
int removeTearParticles(TearSheet<T>& s, const std::vector<std::uint8_t>& mark, bool debris, const TearParams<T>& p,
                        std::vector<std::int32_t>* remap_out) {
  const std::size_t n = s.size();
  if (mark.size() != n) throw InputError("tearing", "mark", "one flag per particle");
  std::vector<std::uint8_t> gone(n, 0);
  for (std::size_t i = 0; i < n; ++i) gone[i] = mark[i] ? 1 : 0;
  if (debris) {
    // Marked particles bonded to a kept one stay, moved between their kept partner and themselves. In index
    // order, each move checked against the triangles that will remain (backed off as in a split).
    for (std::size_t r = 0; r < n; ++r) {
      if (!mark[r]) continue;
      std::int32_t kp = -1;
      for (std::int32_t q = s.pe_offsets[r]; q < s.pe_offsets[r + 1]; ++q)
        if (!mark[s.pe_partner[q]]) {
          kp = s.pe_partner[q];
          break;
        }
      if (kp < 0) continue;
      gone[r] = 0;
      const T u = tear::tearUniform<T>(p.seed, std::uint32_t(std::min<std::size_t>(r, kp)),
                                       std::uint32_t(std::max<std::size_t>(r, kp)), s.step);
      T t = tear::perturbedFraction(T(0.5), p.random_range, u, p.t_lo, p.t_hi);
      for (int attempt = 0; attempt < 5; ++attempt) {
        const Vec3<T> nx = s.x[kp] + (s.x[r] - s.x[kp]) * t, nr = s.rest[kp] + (s.rest[r] - s.rest[kp]) * t;
        bool ok = true;
        for (std::int32_t q = s.pt_offsets[r]; q < s.pt_offsets[r + 1] && ok; ++q) {
          const auto& tr = s.tris[s.pt_tris[q]];
          const int c = tr[0] == std::int32_t(r) ? 0 : (tr[1] == std::int32_t(r) ? 1 : 2);
          const std::int32_t b = tr[(c + 1) % 3], d = tr[(c + 2) % 3];
          ok = tear::moveKeepsTriangle(s.rest[r], nr, s.rest[b], s.rest[d], p.min_area_ratio) &&
               tear::moveKeepsTriangle(s.x[r], nx, s.x[b], s.x[d], p.min_area_ratio);
        }
        if (ok) {
          s.x[r] = nx;
          s.rest[r] = nr;
          break;
        }
        t = T(0.5) * (T(1) + t);  // half way back towards staying in place (t = 1)
      }
    }
  }
  // Triangles: traditional drops any with a removed vertex; debris drops those with a removed vertex or
  // without any unmarked vertex.
  std::vector<std::array<std::int32_t, 3>> tris;
  std::vector<Vec3<T>> refn;
  std::vector<std::uint8_t> used(n, 0);
  for (std::size_t t = 0; t < s.tris.size(); ++t) {
    const auto& tr = s.tris[t];
    bool keep = !gone[tr[0]] && !gone[tr[1]] && !gone[tr[2]];
    if (debris) keep = keep && (!mark[tr[0]] || !mark[tr[1]] || !mark[tr[2]]);
    if (!keep) continue;
    tris.push_back(tr);
    refn.push_back(s.ref_normal[t]);
    for (int c = 0; c < 3; ++c) used[tr[c]] = 1;
  }
  // Compaction: particles that are gone or left without triangles; prefix sum of the kept flags.
  std::vector<std::int32_t> remap(n, -1);
  std::int32_t next = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (used[i]) remap[i] = next++;
  auto compact = [&](auto& arr) {
    for (std::size_t i = 0; i < n; ++i)
      if (remap[i] >= 0) arr[remap[i]] = arr[i];
    arr.resize(std::size_t(next));
  };
  compact(s.rest);
  compact(s.x);
  compact(s.v);
  compact(s.mass);
  compact(s.fixed);
  compact(s.k);
  compact(s.tau_f);
  for (auto& tr : tris)
    for (int c = 0; c < 3; ++c) tr[c] = remap[tr[c]];
  s.tris = std::move(tris);
  s.ref_normal = std::move(refn);
  ++s.step;
  s.rebuildTopology();
  if (remap_out) *remap_out = std::move(remap);
  return int(n) - int(next);
}

#define INC_TEAR_INSTANTIATE(T)                                                                                    \
  template struct TearSheet<T>;                                                                                    \
  template TearSheet<T> makeTearGrid<T>(int, int, double, double, const Vec3d&, double, double);                   \
  template TearSheet<T> makeTearTube<T>(int, int, double, double, double, double, double);                         \
  template void applyTearRegions<T>(TearSheet<T>&, const std::vector<TearRegion>&);                                \
  template void fixTearParticles<T>(TearSheet<T>&, const Vec3d&, const Vec3d&);                                    \
  template PbdModel<T> buildTearPbdModel<T>(const TearSheet<T>&, const TearModelOptions&);                         \
  template TearMeshCheck checkTearMesh<T>(const TearSheet<T>&);                                                    \
  template double tearBoundaryLength<T>(const TearSheet<T>&, bool);                                                \
  template double totalMass<T>(const TearSheet<T>&);                                                               \
  template Vec3d totalMomentum<T>(const TearSheet<T>&);                                                            \
  template int removeTearParticles<T>(TearSheet<T>&, const std::vector<std::uint8_t>&, bool, const TearParams<T>&, \
                                      std::vector<std::int32_t>*);                                                 \
  template std::vector<std::uint8_t> markInBox<T>(const TearSheet<T>&, const Vec3d&, const Vec3d&);                \
  template std::vector<std::uint8_t> markNearSegment<T>(const TearSheet<T>&, const Vec3d&, const Vec3d&, double);

INC_TEAR_INSTANTIATE(float)
INC_TEAR_INSTANTIATE(double)

}  // namespace inc
