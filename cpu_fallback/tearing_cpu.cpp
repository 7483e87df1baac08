// CPU tearing step: the five data-parallel phases of tearing_cpu.h, calling physics/tearing_tresca.h.
#include "cpu_fallback/tearing_cpu.h"

#include "base/parallel.h"
#include "physics/tearing_phases.h"

namespace inc::cpu {

namespace {
template <typename T>
tear::SheetView<T> sheetView(TearSheet<T>& s) {
  tear::SheetView<T> v;
  v.rest = s.rest.data();
  v.x = s.x.data();
  v.v = s.v.data();
  v.mass = s.mass.data();
  v.fixed = s.fixed.data();
  v.k = s.k.data();
  v.tau_f = s.tau_f.data();
  v.tris = s.tris.empty() ? nullptr : s.tris.front().data();  // std::array<int32, 3> is contiguous, 12 bytes
  v.pe_offsets = s.pe_offsets.data();
  v.pe_partner = s.pe_partner.data();
  v.pt_offsets = s.pt_offsets.data();
  v.pt_tris = s.pt_tris.data();
  return v;
}
}  // namespace

template <typename T>
TearStepStats tearStepCpu(TearSheet<T>& s, const TearParams<T>& p, TearCandidates<T>* out, bool rebuild) {
  const std::size_t n = s.size();
  const std::int64_t ni = std::int64_t(n);
  TearCandidates<T> local;
  TearCandidates<T>& c = out ? *out : local;
  c.yield.assign(n, 0);
  c.accept.assign(n, 0);
  c.partner.assign(n, -1);
  c.dir.assign(n, Vec3<T>());
  c.t_pred.assign(n, T(0));

  tear::SheetView<T> view = sheetView(s);
  // Phase 1: detection.
  parallelFor(ni, [&](std::int64_t i) {
    const tear::Detection<T> d = tear::detectYield(view, std::int32_t(i), int(p.criterion), p.break_strain);
    c.yield[i] = d.yield;
    c.partner[i] = d.partner;
    c.dir[i] = d.dir;
    c.t_pred[i] = d.t_pred;
  });
  // Phase 2: independent set.
  parallelFor(ni, [&](std::int64_t i) {
    c.accept[i] = tear::acceptSplit(view, c.yield.data(), std::int32_t(i), p.seed, s.step);
  });
  // Phase 3: exclusive prefix sum (sequential on the CPU; CUB on the GPU).
  std::vector<std::int32_t> rank(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) rank[i + 1] = rank[i] + c.accept[i];
  const std::int32_t splits = rank[n];
  TearStepStats st;
  for (std::size_t i = 0; i < n; ++i) st.yielding += c.yield[i];
  st.splits = splits;
  st.deferred = st.yielding - splits;
  if (splits == 0) {
    ++s.step;
    return st;
  }
  // Phase 4: new particles.
  const std::size_t m = n + std::size_t(splits);
  s.resizeParticles(m);
  view = sheetView(s);
  std::vector<std::int32_t> split_bonds(n, 0), backed(n, 0);
  const bool debris = p.criterion != TearCriterion::Threshold;
  parallelFor(ni, [&](std::int64_t i) {
    if (!c.accept[i]) return;
    const tear::SplitResult r =
        tear::splitParticle(view, std::int32_t(i), n + std::size_t(rank[i]), c.partner[i], c.dir[i], c.t_pred[i],
                            debris, p.random_range, p.t_lo, p.t_hi, p.min_area_ratio, p.seed, s.step);
    split_bonds[i] = r.moved_triangles;
    backed[i] = r.backed_off;
  });
  for (std::size_t i = 0; i < n; ++i) {
    st.moved_triangles += split_bonds[i];
    st.backed_off += backed[i];
  }
  // Phase 5: triangles.
  const std::int64_t nt = std::int64_t(s.tris.size());
  parallelFor(nt, [&](std::int64_t t) {
    tear::rebuildTriangle(view, std::int32_t(t), c.accept.data(), c.dir.data(), rank.data(), std::int32_t(n));
  });
  ++s.step;
  if (rebuild) s.rebuildTopology();
  return st;
}

template TearStepStats tearStepCpu<float>(TearSheet<float>&, const TearParams<float>&, TearCandidates<float>*, bool);
template TearStepStats tearStepCpu<double>(TearSheet<double>&, const TearParams<double>&, TearCandidates<double>*,
                                           bool);

}  // namespace inc::cpu
