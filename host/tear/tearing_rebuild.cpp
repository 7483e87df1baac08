// Rebuild of a torn sheet's adjacency and PBD constraints on the CPU by the device's algorithms (per-particle fans;
// radix sorts): their reference.
#include "host/tear/tearing_rebuild.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "physics/tearing_rebuild.h"

namespace inc {

namespace {

// offsets[p] = first position of owner p in the ascending owners (p = 0 .. n).
template <typename K>
std::vector<std::int32_t> offsetsFromSorted(const std::vector<K>& owners, std::size_t n, int shift) {
  std::vector<std::int32_t> off(n + 1);
  for (std::size_t p = 0; p <= n; ++p)
    off[p] = std::int32_t(tear::lowerBound<K>(owners.data(), std::int64_t(owners.size()), K(K(p) << shift)));
  return off;
}

// Phase 4 for a fixed-arity block whose ids are written: particle -> slot CSR and Jacobi scales.
template <typename T>
void finishBlock(PbdConstraintBlock<T>& b, int arity, std::size_t n, const std::vector<T>& inv_mass) {
  const std::size_t slots = b.ids.size();
  b.offsets.resize(b.rest.size() + 1);
  for (std::size_t c = 0; c < b.offsets.size(); ++c) b.offsets[c] = std::int32_t(arity * c);
  std::vector<std::int32_t> order(slots);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::int32_t u, std::int32_t v) { return b.ids[u] < b.ids[v]; });
  std::vector<std::uint32_t> owner(slots);
  for (std::size_t q = 0; q < slots; ++q) owner[q] = std::uint32_t(b.ids[order[q]]);
  b.particle_slots = order;
  b.particle_offsets = offsetsFromSorted(owner, n, 0);
  b.jacobi_scale.resize(slots);
  for (std::size_t c = 0; c < b.rest.size(); ++c) {
    const T sc = tear::jacobiScaleOf(b.ids.data(), arity, std::int64_t(c), b.particle_offsets.data(), inv_mass.data());
    for (int k = 0; k < arity; ++k) b.jacobi_scale[arity * c + k] = sc;
  }
  b.coloring = ConstraintColoring{};
}

}  // namespace

template <typename T>
TearSortedRebuild<T> rebuildTearSorted(const TearSheet<T>& s, const TearModelOptions& opt) {
  TearSortedRebuild<T> r;
  const std::size_t n = s.size(), nt = s.tris.size(), nh = 3 * nt;
  const int bits = tear::indexBits(std::int64_t(n));
  const std::int32_t* tris = nt ? s.tris.front().data() : nullptr;
  // 1: particle -> triangles.
  std::vector<std::int32_t> corner(nh);
  std::iota(corner.begin(), corner.end(), 0);
  std::stable_sort(corner.begin(), corner.end(), [&](std::int32_t u, std::int32_t v) { return tris[u] < tris[v]; });
  std::vector<std::uint32_t> owner(nh);
  r.pt_tris.resize(nh);
  for (std::size_t q = 0; q < nh; ++q) {
    owner[q] = std::uint32_t(tris[corner[q]]);
    r.pt_tris[q] = corner[q] / 3;
  }
  r.pt_offsets = offsetsFromSorted(owner, n, 0);
  // 2: half-edges by key; heads are unique edges, runs of two get a bending constraint.
  std::vector<std::uint64_t> key(nh);
  std::vector<std::int32_t> opp(nh);
  for (std::size_t h = 0; h < nh; ++h) tear::halfEdge(tris, std::int64_t(h), bits, key[h], opp[h]);
  std::vector<std::int32_t> perm(nh);
  std::iota(perm.begin(), perm.end(), 0);
  std::stable_sort(perm.begin(), perm.end(), [&](std::int32_t u, std::int32_t v) { return key[u] < key[v]; });
  std::vector<std::uint64_t> skey(nh);
  std::vector<std::int32_t> sopp(nh);
  for (std::size_t q = 0; q < nh; ++q) {
    skey[q] = key[perm[q]];
    sopp[q] = opp[perm[q]];
  }
  std::vector<std::int32_t> head(nh), bend(nh), e_idx(nh + 1, 0), b_idx(nh + 1, 0);
  for (std::size_t h = 0; h < nh; ++h) {
    head[h] = tear::runHead(skey.data(), std::int64_t(h)) ? 1 : 0;
    bend[h] = head[h] && tear::runLength(skey.data(), std::int64_t(h), std::int64_t(nh)) == 2 ? 1 : 0;
    e_idx[h + 1] = e_idx[h] + head[h];
    b_idx[h + 1] = b_idx[h] + bend[h];
  }
  const std::size_t ne = std::size_t(e_idx[nh]), nb = std::size_t(b_idx[nh]);
  r.edge_a.resize(ne);
  r.edge_b.resize(ne);
  PbdConstraintBlock<T>& d = r.distance;
  PbdConstraintBlock<T>& b = r.bending;
  d.kind = PbdConstraintKind::Distance;
  b.kind = PbdConstraintKind::Bending;
  d.stiffness = b.stiffness = T(opt.pbd_stiffness);
  d.ids.resize(2 * ne);
  d.rest.resize(ne);
  d.compliance.resize(ne);
  b.ids.resize(4 * nb);
  b.rest.resize(nb);
  b.compliance.resize(nb);
  for (std::size_t h = 0; h < nh; ++h)
    if (head[h])
      tear::writeEdgeConstraints<T>(skey.data(), sopp.data(), std::int64_t(h),
                                    tear::runLength(skey.data(), std::int64_t(h), std::int64_t(nh)), bits, e_idx[h],
                                    b_idx[h], s.rest.data(), T(opt.stretch_compliance), T(opt.bending_compliance),
                                    r.edge_a.data(), r.edge_b.data(), d.ids.data(), d.rest.data(), d.compliance.data(),
                                    b.ids.data(), b.rest.data(), b.compliance.data());
  // 3: particle -> partners, ascending (owner, partner) keys.
  std::vector<std::uint64_t> pk(2 * ne);
  for (std::size_t e = 0; e < ne; ++e) {
    pk[2 * e] = (std::uint64_t(r.edge_a[e]) << bits) | std::uint64_t(r.edge_b[e]);
    pk[2 * e + 1] = (std::uint64_t(r.edge_b[e]) << bits) | std::uint64_t(r.edge_a[e]);
  }
  std::sort(pk.begin(), pk.end());
  r.pe_partner.resize(2 * ne);
  for (std::size_t q = 0; q < 2 * ne; ++q) r.pe_partner[q] = tear::edgeLow(pk[q], bits);
  r.pe_offsets = offsetsFromSorted(pk, n, bits);
  // 4: incidence and Jacobi scales.
  std::vector<T> inv_mass(n);
  for (std::size_t i = 0; i < n; ++i) inv_mass[i] = s.fixed[i] ? T(0) : T(1) / s.mass[i];
  finishBlock(d, 2, n, inv_mass);
  finishBlock(b, 4, n, inv_mass);
  return r;
}

template <typename T>
TearSortedRebuild<T> rebuildTearFans(const TearSheet<T>& s, const TearModelOptions& opt, int fan_cache) {
  TearSortedRebuild<T> r;
  const std::size_t n = s.size(), nt = s.tris.size(), nh = 3 * nt;
  const std::int32_t* tris = nt ? s.tris.front().data() : nullptr;
  // 1: particle -> triangles.
  std::vector<std::int32_t> count(n + 1, 0);
  for (std::size_t h = 0; h < nh; ++h) ++count[std::size_t(tris[h])];
  r.pt_offsets.assign(n + 1, 0);
  for (std::size_t p = 0; p < n; ++p) r.pt_offsets[p + 1] = r.pt_offsets[p] + count[p];
  r.pt_tris.resize(nh);
  for (std::size_t h = 0; h < nh; ++h) {
    const std::size_t p = std::size_t(tris[h]);
    r.pt_tris[std::size_t(r.pt_offsets[p] + --count[p])] = std::int32_t(h / 3);
  }
  for (std::size_t p = 0; p < n; ++p)
    tear::sortRow(r.pt_tris.data() + r.pt_offsets[p], r.pt_offsets[p + 1] - r.pt_offsets[p]);
  tear::Fan fan;
  fan.tris = tris;
  fan.pt_offsets = r.pt_offsets.data();
  fan.pt_tris = r.pt_tris.data();
  // 2: counts and their exclusive scan.
  std::vector<tear::FanCounts> off(n + 1);
  for (std::size_t p = 0; p < n; ++p)
    off[p + 1] = tear::AddFanCounts()(off[p], tear::fanCounts(fan, std::int32_t(p), fan_cache));
  const tear::FanCounts total = off[n];
  const std::size_t ne = std::size_t(total.upper), nb = std::size_t(total.bend_upper);
  if (std::size_t(total.partners) != 2 * ne)
    throw std::logic_error("rebuildTearFans: inconsistent counts (a degenerate or duplicated triangle?)");
  // 3, 4: rows, edges, constraints, incidence.
  PbdConstraintBlock<T>& d = r.distance;
  PbdConstraintBlock<T>& b = r.bending;
  d.kind = PbdConstraintKind::Distance;
  b.kind = PbdConstraintKind::Bending;
  d.stiffness = b.stiffness = T(opt.pbd_stiffness);
  r.pe_offsets.resize(n + 1);
  r.pe_partner.resize(2 * ne);
  r.edge_a.resize(ne);
  r.edge_b.resize(ne);
  d.ids.resize(2 * ne);
  d.rest.resize(ne);
  d.compliance.resize(ne);
  d.particle_offsets.resize(n + 1);
  d.particle_slots.resize(2 * ne);
  b.ids.resize(4 * nb);
  b.rest.resize(nb);
  b.compliance.resize(nb);
  b.particle_offsets.resize(n + 1);
  b.particle_slots.resize(4 * nb);
  tear::FanOutputs<T> o;
  o.off = off.data();
  o.rest = s.rest.data();
  o.stretch_compliance = T(opt.stretch_compliance);
  o.bending_compliance = T(opt.bending_compliance);
  o.pe_offsets = r.pe_offsets.data();
  o.pe_partner = r.pe_partner.data();
  o.edge_a = r.edge_a.data();
  o.edge_b = r.edge_b.data();
  o.dist_ids = d.ids.data();
  o.dist_rest = d.rest.data();
  o.dist_compliance = d.compliance.data();
  o.dist_particle_offsets = d.particle_offsets.data();
  o.dist_particle_slots = d.particle_slots.data();
  o.bend_ids = b.ids.data();
  o.bend_rest = b.rest.data();
  o.bend_compliance = b.compliance.data();
  o.bend_particle_offsets = b.particle_offsets.data();
  o.bend_particle_slots = b.particle_slots.data();
  for (std::size_t p = 0; p <= n; ++p) tear::writeFanOffsets(o, std::int32_t(p));
  for (std::size_t p = 0; p < n; ++p) tear::writeFanEdges(fan, o, std::int32_t(p), fan_cache);
  for (std::size_t e = 0; e < ne; ++e) tear::writeLowerDistanceSlot(o, std::int64_t(e));
  // The bending rows from the bending constraints (the device counts and places them through atomics and sorts).
  fillParticleSlots(b, n);
  // 5: offsets and Jacobi scales, as commitBlockIncidence.
  std::vector<T> inv_mass(n);
  for (std::size_t i = 0; i < n; ++i) inv_mass[i] = s.fixed[i] ? T(0) : T(1) / s.mass[i];
  for (PbdConstraintBlock<T>* blk : {&d, &b}) {
    const int arity = blk == &d ? 2 : 4;
    blk->offsets.resize(blk->rest.size() + 1);
    for (std::size_t c = 0; c < blk->offsets.size(); ++c) blk->offsets[c] = std::int32_t(arity * c);
    blk->jacobi_scale.resize(blk->ids.size());
    for (std::size_t c = 0; c < blk->rest.size(); ++c) {
      const T sc =
          tear::jacobiScaleOf(blk->ids.data(), arity, std::int64_t(c), blk->particle_offsets.data(), inv_mass.data());
      for (int k = 0; k < arity; ++k) blk->jacobi_scale[std::size_t(arity) * c + std::size_t(k)] = sc;
    }
    blk->coloring = ConstraintColoring{};
  }
  return r;
}

template TearSortedRebuild<float> rebuildTearSorted<float>(const TearSheet<float>&, const TearModelOptions&);
template TearSortedRebuild<double> rebuildTearSorted<double>(const TearSheet<double>&, const TearModelOptions&);
template TearSortedRebuild<float> rebuildTearFans<float>(const TearSheet<float>&, const TearModelOptions&, int);
template TearSortedRebuild<double> rebuildTearFans<double>(const TearSheet<double>&, const TearModelOptions&, int);

}  // namespace inc
