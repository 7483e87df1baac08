// CPU PBD/XPBD frame: predict, per-block Jacobi (slot output + per-particle gather) or coloured Gauss-Seidel, contacts, velocities, radii.
#include "cpu_fallback/pbd_solver_cpu.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "cpu_fallback/parallel.h"
#include "physics/pbd_block.h"
#include "physics/pbd_volume.h"

namespace inc::cpu {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// parallelFor above a size where a parallel region pays for itself; below it a plain loop (same results:
// every body writes only its own outputs). A PBD frame opens hundreds of regions, so for small models the
// fork/join cost would dominate, and worse on a loaded machine.
constexpr std::int64_t kParallelMin = 2048;
template <typename Body>
void loop(std::int64_t n, Body&& body) {
  if (n >= kParallelMin) {
    parallelFor(n, body);
  } else {
    for (std::int64_t i = 0; i < n; ++i) body(i);
  }
}

// The same for constraint projections, weighted by the block's mean slots per constraint: a shape-matching or
// Laplacian cluster of ~15 members costs as much as ~7 distance constraints, so a Gauss-Seidel colour of a
// few hundred clusters is worth a parallel region (10^4 spheres: ~1,000 clusters per colour ran serially).
template <typename Body>
void constraintLoop(std::int64_t n, std::int64_t slots_per_constraint, Body&& body) {
  if (n * std::max<std::int64_t>(slots_per_constraint, 2) >= 2 * kParallelMin) {
    parallelFor(n, body);
  } else {
    for (std::int64_t i = 0; i < n; ++i) body(i);
  }
}

template <typename T>
class PbdCpuBackend final : public PbdBackend<T> {
 public:
  BackendKind kind() const override { return BackendKind::Cpu; }

  void setModel(const PbdModel<T>& model) override {
    model_ = model;
    const std::size_t n = model_.size();
    state_.positions = model_.rest_positions;
    state_.velocities.assign(n, Vec3<T>());
    state_.radii = model_.rest_radii;
    state_.rotations.assign(n, pbd::Quat<T>{});
    x_prev_.assign(n, Vec3<T>());
    w_.assign(n, T(0));
    radii_next_.assign(n, T(0));
    lambda_.resize(model_.blocks.size());
    slot_corr_.resize(model_.blocks.size());
    for (std::size_t b = 0; b < model_.blocks.size(); ++b) {
      lambda_[b].assign(model_.blocks[b].multiplierCount(), Vec3<T>());
      slot_corr_[b].assign(model_.blocks[b].slotCount(), Vec3<T>());
    }
  }

  void setState(const PbdState<T>& s) override {
    const std::size_t n = model_.size();
    if (s.positions.size() != n || s.velocities.size() != n || s.radii.size() != n || s.rotations.size() != n)
      throw InputError("pbd state", "size", "state arrays must have one entry per particle");
    state_ = s;
  }
  void getState(PbdState<T>& s) const override { s = state_; }

  MemoryReport memory() const override {
    MemoryReport m;
    const std::size_t n = model_.size();
    m.host_bytes = n * (4 * sizeof(Vec3<T>) + 4 * sizeof(T) + sizeof(pbd::Quat<T>));
    for (std::size_t b = 0; b < model_.blocks.size(); ++b) {
      const auto& bl = model_.blocks[b];
      m.host_bytes += bl.ids.size() * (2 * sizeof(std::int32_t) + sizeof(T) + 2 * sizeof(Vec3<T>)) +
                      bl.multiplierCount() * (sizeof(Vec3<T>) + sizeof(T)) + bl.count() * sizeof(T);
    }
    return m;
  }

  PbdFrameStats advanceFrame(const PbdStepParams<T>& p, const PbdFrameInput<T>& in) override {
    const std::size_t n = model_.size();
    validateFrameInput(n, p, in);
    PbdFrameStats st;
    double t_predict = 0, t_constraints = 0, t_collisions = 0, t_velocities = 0, t_volume = 0;
    const T dt = p.frame_dt / T(p.substeps);
    const T damp = std::exp(-p.damping * dt);
    const std::int64_t ni = std::int64_t(n);
    Vec3<T>* x = state_.positions.data();
    Vec3<T>* v = state_.velocities.data();
    const T* r = state_.radii.data();

    // This frame's inverse masses: kinematic (grasped) particles are prescribed, so they get w = 0.
    w_ = model_.inv_mass;
    for (std::int32_t id : in.kinematic_ids) w_[id] = T(0);
    const int nt = int(in.tools_from.size());

    pbd::SolveContext<T> ctx;
    ctx.x = x;
    ctx.w = w_.data();
    ctx.mass = model_.masses.data();
    ctx.rotation = state_.rotations.data();
    ctx.xpbd = p.xpbd;
    ctx.dt = dt;
    ctx.jacobi = p.solver == PbdSolverKind::Jacobi;
    ctx.omega = p.jacobi_omega;
    ctx.rotation_iterations = p.rotation_iterations;
    if (!ctx.jacobi)
      for (const auto& b : model_.blocks)
        if (b.solve) st.colors += b.coloring.colorCount();

    for (int s = 0; s < p.substeps; ++s) {
      const T t_end = T(s + 1) / T(p.substeps);
      auto t0 = Clock::now();
      loop(ni, [&](std::int64_t i) {
        pbd::predictParticle(x[i], v[i], x_prev_[i], w_[i], p.gravity, damp, dt);
      });
      for (std::size_t k = 0; k < in.kinematic_ids.size(); ++k)
        x[in.kinematic_ids[k]] = pbd::lerp(in.kinematic_from[k], in.kinematic_to[k], t_end);
      for (auto& l : lambda_) std::fill(l.begin(), l.end(), Vec3<T>());
      attach_lambda_.assign(in.attach_ids.size(), Vec3<T>());
      t_predict += msSince(t0);

      for (int it = 0; it < p.iterations; ++it) {
        t0 = Clock::now();
        for (std::size_t bi = 0; bi < model_.blocks.size(); ++bi) {
          const auto& b = model_.blocks[bi];
          if (!b.solve) continue;
          const pbd::BlockView<T> view = blockView(bi);
          const std::int64_t spc = b.count() ? std::int64_t(b.slotCount() / b.count()) : 1;
          if (ctx.jacobi) {
            constraintLoop(std::int64_t(b.count()), spc, [&](std::int64_t c) { pbd::projectConstraint(view, int(c), ctx); });
            loop(ni, [&](std::int64_t i) { x[i] += pbd::gatherCorrection(view, std::int32_t(i)); });
          } else {
            const ConstraintColoring& col = b.coloring;
            for (int k = 0; k < col.colorCount(); ++k) {
              const std::int32_t c0 = col.color_offsets[k], c1 = col.color_offsets[k + 1];
              constraintLoop(std::int64_t(c1 - c0), spc,
                             [&](std::int64_t q) { pbd::projectConstraint(view, col.order[c0 + q], ctx); });
            }
          }
        }
        loop(std::int64_t(in.attach_ids.size()), [&](std::int64_t k) {
          const std::int32_t id = in.attach_ids[k];
          pbd::projectAttachment(x[id], w_[id], pbd::lerp(in.attach_from[k], in.attach_to[k], t_end),
                                 in.attach_compliance[k], p.xpbd, dt, attach_lambda_[k]);
        });
        t_constraints += msSince(t0);
        t0 = Clock::now();
        loop(ni, [&](std::int64_t i) {
          if (w_[i] > T(0))
            x[i] = pbd::resolveContacts(x[i], r[i], model_.planes.data(), int(model_.planes.size()), model_.boxes.data(),
                                        int(model_.boxes.size()), in.tools_from.data(), in.tools_to.data(), nt, t_end);
        });
        t_collisions += msSince(t0);
      }

      t0 = Clock::now();
      const T inv_dt = T(1) / dt;
      loop(ni, [&](std::int64_t i) { v[i] = (x[i] - x_prev_[i]) * inv_dt; });
      t_velocities += msSince(t0);
    }
    st.iterations = p.substeps * p.iterations;

    // Rotations for skinning when the shape-matching block is only kept for them.
    if (model_.rotation_block >= 0 && !model_.blocks[model_.rotation_block].solve) {
      auto t0 = Clock::now();
      const pbd::BlockView<T> view = blockView(std::size_t(model_.rotation_block));
      loop(std::int64_t(view.count), [&](std::int64_t c) { pbd::updateClusterRotation(view, int(c), ctx); });
      t_constraints += msSince(t0);
    }

    {
      auto t0 = Clock::now();
      updateRadii(p, in, st);
      t_volume = msSince(t0);
    }

    // Residual of the distance constraints (after the last substep, with its multipliers).
    double rmax = 0, rsum = 0;
    std::size_t rcount = 0;
    for (std::size_t bi = 0; bi < model_.blocks.size(); ++bi) {
      if (model_.blocks[bi].kind != PbdConstraintKind::Distance || !model_.blocks[bi].solve) continue;
      const pbd::BlockView<T> view = blockView(bi);
      for (int c = 0; c < view.count; ++c) {
        const double res = double(pbd::distanceResidual(view, c, x, p.xpbd, dt));
        rmax = std::max(rmax, res);
        rsum += res * res;
        ++rcount;
      }
    }
    st.residual_max = rmax;
    st.residual_rms = rcount ? std::sqrt(rsum / double(rcount)) : 0.0;

    for (std::size_t i = 0; i < n; ++i)
      if (!isFinite(x[i]) || !isFinite(v[i]) || !std::isfinite(double(r[i]))) {
        st.finite = false;
        st.failure_particle = std::int64_t(i);
        break;
      }
    st.stages = {{"predict", t_predict}, {"constraints", t_constraints}, {"collisions", t_collisions},
                 {"velocities", t_velocities}, {"volume", t_volume}};
    return st;
  }

 private:
  pbd::BlockView<T> blockView(std::size_t bi) {
    const PbdConstraintBlock<T>& b = model_.blocks[bi];
    pbd::BlockView<T> v;
    v.kind = int(b.kind);
    v.count = int(b.count());
    v.stiffness = b.stiffness;
    v.offsets = b.offsets.data();
    v.ids = b.ids.data();
    v.rest = b.rest.data();
    v.rest_vec = b.rest_vec.data();
    v.compliance = b.compliance.data();
    v.jacobi_scale = b.jacobi_scale.data();
    v.particle_offsets = b.particle_offsets.data();
    v.particle_slots = b.particle_slots.data();
    v.lambda = lambda_[bi].data();
    v.slot_corr = slot_corr_[bi].data();
    return v;
  }

  // Local volume preservation (physics/pbd_volume.h): spheres near a tool get the radius at which their
  // power-cell volume is back at rest; the rest return to their rest radius. Jacobi passes (read radii,
  // write radii_next) make it independent of the order.
  void updateRadii(const PbdStepParams<T>& p, const PbdFrameInput<T>& in, PbdFrameStats& st) {
    const std::size_t n = model_.size();
    const std::int64_t ni = std::int64_t(n);
    const bool have_volume = p.volume_preservation && model_.rest_cell_volume.size() == n && !model_.ball_samples.empty();
    std::vector<std::uint8_t> active(n, 0);
    if (have_volume) {
      loop(ni, [&](std::int64_t i) {
        if (p.volume_influence < T(0)) {
          active[i] = 1;
          return;
        }
        for (std::size_t k = 0; k < in.tools_to.size(); ++k)
          if (pbd::capsuleDistance(state_.positions[i], in.tools_to[k]) <= model_.rest_radii[i] + p.volume_influence) {
            active[i] = 1;
            return;
          }
      });
    }
    Vec3<T>* x = state_.positions.data();
    for (int pass = 0; pass < (have_volume ? p.volume_passes : 1); ++pass) {
      loop(ni, [&](std::int64_t i) {
        const T r0 = model_.rest_radii[i];
        if (!active[i]) {
          radii_next_[i] = r0;
          return;
        }
        const std::int32_t b = model_.overlap_offsets[i], e = model_.overlap_offsets[i + 1];
        radii_next_[i] = pbd::radiusForCellVolume(x[i], r0, r0 * p.max_radius_growth, model_.rest_cell_volume[i], x,
                                                  state_.radii.data(), model_.overlap_ids.data() + b, e - b,
                                                  model_.ball_samples.data(), int(model_.ball_samples.size()),
                                                  p.bisection_steps);
      });
      state_.radii.swap(radii_next_);
    }
    st.volume_active = 0;
    st.max_radius_ratio = 1.0;
    for (std::size_t i = 0; i < n; ++i) {
      st.volume_active += active[i];
      if (model_.rest_radii[i] > T(0))
        st.max_radius_ratio = std::max(st.max_radius_ratio, double(state_.radii[i] / model_.rest_radii[i]));
    }
  }

  PbdModel<T> model_;
  PbdState<T> state_;
  std::vector<Vec3<T>> x_prev_;
  std::vector<T> w_;
  std::vector<T> radii_next_;
  std::vector<std::vector<Vec3<T>>> lambda_;
  std::vector<std::vector<Vec3<T>>> slot_corr_;
  std::vector<Vec3<T>> attach_lambda_;
};

}  // namespace

template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdCpuBackend() {
  return std::make_unique<PbdCpuBackend<T>>();
}

template std::unique_ptr<PbdBackend<float>> makePbdCpuBackend<float>();
template std::unique_ptr<PbdBackend<double>> makePbdCpuBackend<double>();

}  // namespace inc::cpu
