// CPU MLS solver: drift, coupling, pass 1 (stress) and pass 2 (force gather + kick) on one thread team per frame,
// serial reductions.
#include "cpu_fallback/mls_solver_cpu.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "base/parallel.h"
#include "cpu_fallback/mls_pair_sums_cpu.h"
#include "physics/mls_passes.h"

namespace inc::cpu {

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Below this many particles a pass outside the substep loop runs serially: an OpenMP region costs more than the
// work (and far more on a loaded machine). Gather passes give identical results either way.
constexpr std::int64_t kSerialBelow = 2048;

// The substep loop runs on a team (one parallel region per frame, a barrier between passes, base/team.h)
// with one thread per this many particles: a pass costs ~0.1-0.2 us per particle, a barrier ~0.5 us.
constexpr std::int64_t kParticlesPerThread = 256;

template <typename Body>
void forEachParticle(std::int64_t n, Body&& body) {
  if (n < kSerialBelow) {
    for (std::int64_t i = 0; i < n; ++i) body(i);
  } else {
    parallelFor(n, body);
  }
}

template <typename T>
void checkSize(const std::vector<T>& v, std::size_t n, const char* what) {
  if (v.size() != n)
    throw std::invalid_argument(std::string("MlsSolver: ") + what + " has " + std::to_string(v.size()) +
                                " entries for " + std::to_string(n) + " particles");
}

}  // namespace

template <typename T>
MlsCpuSolver<T>::MlsCpuSolver(MlsModel<T> model) : model_(std::move(model)) {
  state_.resize(model_.size());
  stiffening_out_.assign(model_.size(), T(1));
  elastic_force_.assign(model_.size(), Vec3<T>());
  safety_ = model_.safety;
  buildPairTables();
}

// The rest configuration's share of every pair term, once per model (the model changes only on a rebuild): the
// passes then gather 9 products per pair and evaluate no kernel weight. x_ij and w_ij are evaluated in precision
// T exactly as the recomputing passes do (in double, a pair at the edge of the support could get a weight that
// rounds to a float32 denormal, and every product with a denormal costs a microcode assist).
template <typename T>
void MlsCpuSolver<T>::buildPairTables() {
  const std::int64_t n = std::int64_t(model_.size());
  const NeighborLists& nb = model_.neighbors;
  // One spare entry: the vector loops read a 3-vector as 4 floats (cpu_fallback/mls_pair_sums_cpu.cpp).
  pair_gradient_.assign(nb.indices.size() + 1, Vec3<T>());
  pair_force_.assign(nb.indices.size() + 1, Vec3<T>());
  weighted_sum_.assign(std::size_t(n), Vec3<T>());
  forEachParticle(n, [&](std::int64_t i) {
    const Vec3<T> xi = model_.rest[std::size_t(i)];
    const Mat3<T>& ainv = model_.moment_inverse[std::size_t(i)];
    Vec3<T> sum;
    for (std::int64_t p = nb.offsets[std::size_t(i)]; p < nb.offsets[std::size_t(i) + 1]; ++p) {
      const Vec3<T> xij = model_.rest[std::size_t(nb.indices[std::size_t(p)])] - xi;
      mlsPairTerms(ainv, xij, mlsKernelWeight(norm2(xij), model_.support), pair_gradient_[std::size_t(p)],
                   pair_force_[std::size_t(p)]);
      sum += pair_force_[std::size_t(p)];
    }
    weighted_sum_[std::size_t(i)] = sum;
  });
}

template <typename T>
int MlsCpuSolver<T>::teamThreads() const {
  return int(
      std::max<std::int64_t>(1, std::min<std::int64_t>(threadCount(), std::int64_t(size()) / kParticlesPerThread)));
}

template <typename T>
std::vector<Vec3d> MlsCpuSolver<T>::restPositions() const {
  std::vector<Vec3d> out(model_.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = model_.origin + Vec3d(model_.rest[i]);
  return out;
}

template <typename T>
MlsView<T> MlsCpuSolver<T>::view() {
  MlsView<T> s = makeMlsView(model_, state_);
  s.pair_gradient = pair_gradient_.data();
  s.pair_force = pair_force_.data();
  s.weighted_sum = weighted_sum_.data();
  s.elastic_force = elastic_force_.data();
  if (bladeOn()) s.blade = &blade_t_;
  if (staticsOn()) s.statics = &statics_t_;
  if (!cg_rest_centre_.empty()) {
    s.coupling_group = particle_group_.data();
    s.coupling_force = cg_force_.data();
    s.coupling_torque = cg_torque_.data();
    s.coupling_centroid = cg_centroid_.data();
  }
  return s;
}

template <typename T>
CouplingView<T> MlsCpuSolver<T>::couplingView() {
  CouplingView<T> c;
  c.groups = std::int32_t(cg_rest_centre_.size());
  c.member_offsets = cg_member_offsets_.data();
  c.members = cg_members_.data();
  c.rest_centre = cg_rest_centre_.data();
  c.spring_offsets = cg_spring_offsets_.data();
  c.anchor = cg_anchor_.data();
  c.rest_length = cg_rest_length_.data();
  c.stiffness = cg_stiffness_.data();
  c.group_displacement = cg_displacement_.data();
  c.member_force = cg_force_.data();
  c.member_rest = model_.rest.data();
  c.rest_centroid = cg_centroid_.data();
  c.rest_gram = cg_gram_.data();
  c.inertia_inverse = cg_inertia_inverse_.data();
  c.rotation = cg_rotation_.data();
  c.member_torque = cg_torque_.data();
  return c;
}

template <typename T>
void MlsCpuSolver<T>::couplingPass() {
  if (cg_rest_centre_.empty()) return;
  const CouplingView<T> c = couplingView();
  const Vec3<T>* u = state_.displacement.data();
  forEachParticle(c.groups, [&](std::int64_t g) { couplingGroupPass(c, u, std::int32_t(g)); });
}

template <typename T>
void MlsCpuSolver<T>::setCouplingGroups(const MlsCouplingGroups& g) {
  validateMlsCouplingGroups(g, size());
  cg_member_offsets_ = g.member_offsets;
  cg_members_ = g.members;
  cg_spring_offsets_ = g.spring_offsets;
  cg_rest_centre_.resize(g.size());
  for (std::size_t k = 0; k < g.size(); ++k) cg_rest_centre_[k] = Vec3<T>(g.rest_centres[k] - model_.origin);
  cg_rest_length_.assign(g.rest_lengths.begin(), g.rest_lengths.end());
  cg_stiffness_.assign(g.stiffnesses.begin(), g.stiffnesses.end());
  // Until anchors arrive every spring sits at its rest length from the group's rest centre along x (no force).
  cg_anchor_.resize(g.springs());
  for (std::size_t k = 0; k < g.size(); ++k)
    for (std::int32_t s = g.spring_offsets[k]; s < g.spring_offsets[k + 1]; ++s)
      cg_anchor_[std::size_t(s)] = cg_rest_centre_[k] + Vec3<T>(cg_rest_length_[std::size_t(s)], T(0), T(0));
  cg_displacement_.assign(g.size(), Vec3<T>());
  cg_force_.assign(g.size(), Vec3<T>());
  particle_group_.assign(size(), -1);
  for (std::size_t k = 0; k < g.size(); ++k)
    for (std::int32_t p = g.member_offsets[k]; p < g.member_offsets[k + 1]; ++p)
      particle_group_[std::size_t(g.members[std::size_t(p)])] = std::int32_t(k);
  if (g.size() == 0) particle_group_.clear();
  const MlsCouplingFrames frames = mlsCouplingFrames(g, restPositions());
  MlsCouplingFrameArrays<T> fa = mlsCouplingFrameArrays<T>(frames, model_.origin);
  cg_centroid_ = std::move(fa.centroid);
  cg_gram_ = std::move(fa.gram);
  cg_inertia_inverse_ = std::move(fa.inertia_inverse);
  cg_rotation_.assign(g.size(), pbd::Quat<T>());
  cg_torque_.assign(g.size(), Mat3<T>());
  std::vector<double> mass(model_.mass.begin(), model_.mass.end());
  setCouplingStableStep(mlsCouplingStableStep(g, mass, &frames));
  forces_valid_ = false;
}

template <typename T>
void MlsCpuSolver<T>::setCouplingAnchors(const std::vector<Vec3d>& anchors) {
  checkSize(anchors, cg_rest_length_.size(), "coupling anchors");
  for (std::size_t s = 0; s < anchors.size(); ++s) cg_anchor_[s] = Vec3<T>(anchors[s] - model_.origin);
  coupling_stale_ = true;  // the elastic part of the forces stays valid (substeps refreshes only the coupling)
}

template <typename T>
void MlsCpuSolver<T>::couplingDisplacements(std::vector<Vec3d>& out) {
  couplingPass();
  out.resize(cg_displacement_.size());
  for (std::size_t g = 0; g < out.size(); ++g) out[g] = Vec3d(cg_displacement_[g]);
}

template <typename T>
void MlsCpuSolver<T>::computeForces() {
  couplingPass();
  MlsView<T> s = view();
  s.stiffening = stiffening_out_.data();
  const bool avx2 = mlsPairSumsUseAvx2();
  forEachParticle(s.n, [&](std::int64_t i) { mlsStressRange(s, i, i + 1, avx2); });
  forEachParticle(s.n, [&](std::int64_t k) { mlsForceRange(s, k, k + 1, T(0), false, avx2); });
  forces_valid_ = true;
  coupling_stale_ = false;
}

// n leapfrog substeps on one team: drift | coupling | stress | force + kick, a barrier where a pass reads what
// another thread wrote. Every pass is a gather over its own items, so the result does not depend on the split.
// The force pass needs no barrier after it: the next drift touches only its own particles, and the next stress
// pass (which overwrites the stress moments the force pass reads) starts after the drift's barrier, which every
// thread reaches only once its force share is done.
template <typename T>
void MlsCpuSolver<T>::substeps(T dt, int n, MlsFrameStats* stats) {
  if (!forces_valid_) {
    computeForces();
  } else if (coupling_stale_) {
    // New anchors at the same displacement: the springs' share changes, the elastic part does not (eqs. 11-12).
    couplingPass();
    const MlsView<T> s = view();
    forEachParticle(s.n, [&](std::int64_t k) { mlsCouplingRefresh(s, k); });
    coupling_stale_ = false;
  }
  if (n <= 0) return;
  blade_t_ = bladeContact<T>(double(dt), n);
  statics_t_ = staticContacts<T>();
  const MlsView<T> s = view();
  MlsView<T> last = s;  // the last stress pass also leaves each particle's stiffening for reduce()
  last.stiffening = stiffening_out_.data();
  const bool coupled = !cg_rest_centre_.empty();
  const CouplingView<T> c = couplingView();
  const std::int64_t groups = c.groups;
  const T half = T(0.5) * dt;
  const bool avx2 = mlsPairSumsUseAvx2();
  double ms[4] = {0.0, 0.0, 0.0, 0.0};  // integrate, coupling, stress, forces (the lead thread's clock)
  team_.run(teamThreads(), [&](const Team& t) {
    auto t0 = std::chrono::steady_clock::now();
    const auto lap = [&](int stage) {
      if (!t.lead() || !stats) return;
      const auto t1 = std::chrono::steady_clock::now();
      ms[stage] += std::chrono::duration<double, std::milli>(t1 - t0).count();
      t0 = t1;
    };
    for (int step = 0; step < n; ++step) {
      const int remaining = n - step;
      for (std::int64_t k = t.begin(s.n), e = t.end(s.n); k < e; ++k) mlsDriftPass(s, k, dt, remaining);
      t.barrier();
      lap(0);
      // The groups' spring forces at the drifted displacement, for the force gather. The group pass and the stress
      // pass both only read the displacement and write disjoint arrays: one phase, one barrier (as the GPU's
      // stressCouplingKernel), so neither phase's imbalance waits alone.
      if (coupled)
        for (std::int64_t g = t.begin(groups), e = t.end(groups); g < e; ++g)
          couplingGroupPass(c, s.displacement, std::int32_t(g));
      lap(1);
      const MlsView<T>& sp = step == n - 1 ? last : s;
      mlsStressRange(sp, t.begin(s.n), t.end(s.n), avx2);
      t.barrier();
      lap(2);
      mlsForceRange(s, t.begin(s.n), t.end(s.n), half, true, avx2);
      lap(3);
    }
  });
  if (stats) {
    stats->ms_integrate += ms[0];
    stats->ms_coupling += ms[1];
    stats->ms_stress += ms[2];
    stats->ms_forces += ms[3];
  }
}

template <typename T>
void MlsCpuSolver<T>::step(double dt, int n) {
  if (!(dt > 0) || !(dt <= stableTimeStep() * (1.0 + 1e-12)))
    throw InputError(model_.source, "dt",
                     "time step " + std::to_string(dt) + " s is outside (0, stable limit " +
                         std::to_string(stableTimeStep()) + " s]; refused");
  if (n <= 0) return;
  substeps(T(dt), n, nullptr);
}

template <typename T>
MlsFrameStats MlsCpuSolver<T>::advance(double frame_dt, int fixed_substeps) {
  MlsFrameStats st;
  st.substeps = planFrame(frame_dt, fixed_substeps, model_.source);
  if (st.substeps == 0) return unplannableFrame();
  st.dt = frame_dt / st.substeps;
  substeps(T(st.dt), st.substeps, &st);
  const auto t0 = std::chrono::steady_clock::now();
  st.totals = reduce();
  st.ms_reduce = msSince(t0);
  return st;
}

template <typename T>
MlsReduction MlsCpuSolver<T>::reduce() {
  if (!forces_valid_) computeForces();
  MlsState<T>& st = state_;
  const MlsView<T> s = view();
  MlsReduction r;
  double max_u2 = 0.0;
  // Serial, in index order, in double: deterministic and independent of the thread count.
  for (std::int64_t k = 0; k < s.n; ++k) {
    if (!mlsParticleFinite(s, k)) {
      if (r.finite) {
        r.finite = false;
        r.first_bad = k;
        r.bad_stage = !(isFinite(st.displacement[std::size_t(k)]) && isFinite(st.velocity[std::size_t(k)]))
                          ? "integrate"
                      : !isFinite(st.force[std::size_t(k)]) ? "forces"
                                                            : "stress";
      }
      continue;
    }
    r.kinetic_energy += double(mlsKineticEnergy(s, k));
    r.potential_energy += double(mlsGravityEnergy(s, k));
    r.elastic_energy += double(st.energy[std::size_t(k)]);
    max_u2 = std::max(max_u2, double(norm2(st.displacement[std::size_t(k)])));
  }
  r.max_displacement = std::sqrt(max_u2);
  // Stiffening: left by the last stress pass at this displacement (max is order independent).
  for (const T k : stiffening_out_) r.stiffening = std::max(r.stiffening, double(k));
  noteReduction(r);
  return r;
}

template <typename T>
void MlsCpuSolver<T>::setDisplacements(const std::vector<Vec3d>& u) {
  checkSize(u, size(), "displacements");
  for (std::size_t i = 0; i < u.size(); ++i) state_.displacement[i] = Vec3<T>(u[i]);
  forces_valid_ = false;
  forgetStiffening();
}

template <typename T>
void MlsCpuSolver<T>::setVelocities(const std::vector<Vec3d>& v) {
  checkSize(v, size(), "velocities");
  for (std::size_t i = 0; i < v.size(); ++i) state_.velocity[i] = Vec3<T>(v[i]);
}

template <typename T>
void MlsCpuSolver<T>::displacements(std::vector<Vec3d>& out) const {
  out.resize(size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3d(state_.displacement[i]);
}

template <typename T>
void MlsCpuSolver<T>::velocities(std::vector<Vec3d>& out) const {
  out.resize(size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3d(state_.velocity[i]);
}

template <typename T>
void MlsCpuSolver<T>::forces(std::vector<Vec3d>& out) const {
  out.resize(size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3d(state_.force[i]);
}

template <typename T>
void MlsCpuSolver<T>::energies(std::vector<double>& out) const {
  out.resize(size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = double(state_.energy[i]);
}

template <typename T>
void MlsCpuSolver<T>::setPrescribed(const std::vector<std::int32_t>& particles, const std::vector<Vec3d>& targets) {
  checkSize(targets, particles.size(), "prescribed targets");
  for (std::size_t p = 0; p < particles.size(); ++p) {
    const std::int32_t i = particles[p];
    if (i < 0 || std::size_t(i) >= size()) throw std::invalid_argument("MlsSolver: prescribed particle out of range");
    if (model_.kind[std::size_t(i)] == kMlsFixed) continue;
    model_.kind[std::size_t(i)] = kMlsPrescribed;
    state_.target[std::size_t(i)] = Vec3<T>(targets[p]);
  }
}

template <typename T>
void MlsCpuSolver<T>::release(const std::vector<std::int32_t>& particles) {
  for (const std::int32_t i : particles) {
    if (i < 0 || std::size_t(i) >= size()) throw std::invalid_argument("MlsSolver: released particle out of range");
    if (model_.kind[std::size_t(i)] == kMlsPrescribed) model_.kind[std::size_t(i)] = kMlsFree;
  }
}

template <typename T>
void MlsCpuSolver<T>::saveCheckpoint() {
  saved_u_ = state_.displacement;
  saved_v_ = state_.velocity;
  saved_rotation_ = cg_rotation_;  // the groups' warm starts: a retried step repeats the same extraction
}

template <typename T>
void MlsCpuSolver<T>::restoreCheckpoint() {
  if (saved_u_.size() != size()) return;  // nothing saved yet
  state_.displacement = saved_u_;
  state_.velocity = saved_v_;
  if (saved_rotation_.size() == cg_rotation_.size()) cg_rotation_ = saved_rotation_;
  forces_valid_ = false;
  forgetStiffening();
}

template <typename T>
MemoryReport MlsCpuSolver<T>::memory() const {
  MemoryReport m;
  m.host_bytes = model_.bytes() + state_.bytes() +
                 (saved_u_.size() + saved_v_.size() + pair_gradient_.size() + pair_force_.size() +
                  weighted_sum_.size() + elastic_force_.size()) *
                     sizeof(Vec3<T>) +
                 stiffening_out_.size() * sizeof(T) +
                 (cg_members_.size() + particle_group_.size() + 2 * cg_member_offsets_.size()) * sizeof(std::int32_t) +
                 (cg_rest_centre_.size() * 3 + cg_anchor_.size()) * sizeof(Vec3<T>) +
                 cg_rest_length_.size() * 2 * sizeof(T);
  return m;
}

template class MlsCpuSolver<float>;
template class MlsCpuSolver<double>;

std::unique_ptr<MlsSolver> makeMlsSolverCpu(MlsModel<float> model) {
  return std::make_unique<MlsCpuSolver<float>>(std::move(model));
}
std::unique_ptr<MlsSolver> makeMlsSolverCpu(MlsModel<double> model) {
  return std::make_unique<MlsCpuSolver<double>>(std::move(model));
}

}  // namespace inc::cpu
