// NodalRegion: sphere -> points conversion during a stroke, visibility-filtered supports, MLS rebuilds, coupling groups.
#include "host/cut_nodal_region.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>

#include "cpu_fallback/parallel.h"
#include "host/cut_nodal_points.h"
#include "host/elapsed_ms.h"
#include "host/input_error.h"
#include "physics/cut_coupling.h"

namespace inc {

namespace {

const double kPi = 3.141592653589793;

bool insideBox(const Vec3d& p, const FixedRegion& r) {
  return p.x >= r.min.x && p.x <= r.max.x && p.y >= r.min.y && p.y <= r.max.y && p.z >= r.min.z && p.z <= r.max.z;
}

}  // namespace

NodalRegion::NodalRegion(const MetaballModel& base, const NodalRegionSettings& s, std::vector<const SweptSurface*> earlier)
    : base_(base), settings_(s), earlier_(std::move(earlier)) {
  if (s.samples_per_diameter < 1 || s.samples_per_diameter > 64)
    throw InputError(s.mls.source, "cutting.samples_per_diameter", "must be in [1, 64]");
  if (s.backend == BackendKind::Auto) throw InputError(s.mls.source, "solver.backend", "the nodal region needs a resolved backend");
  if (!(s.youngs_modulus > 0)) throw InputError(s.mls.source, "material.youngs_modulus_pa", "must be > 0");
  role_.assign(base_.size(), SphereRole::Pbd);
  double rmean = 0.0;
  for (double r : base_.rest_radii) rmean += r / double(std::max<std::size_t>(1, base_.size()));
  spacing_ = 2.0 * rmean / s.samples_per_diameter;
  supports_ = StrokeSupports(s.mls.support_factor * spacing_, earlier_);
  adjacency_.resize(base_.size());
  sphere_points_.resize(base_.size());
  for (std::size_t l = 0; l < base_.links.size(); ++l) {
    const auto& e = base_.links[l];
    const double d = base_.link_rest_lengths[l];
    const double rbar = 0.5 * (base_.rest_radii[std::size_t(e[0])] + base_.rest_radii[std::size_t(e[1])]);
    // The PBD link's compliance (host/pbd_builders.cpp) as a Hooke spring: k = 1 / alpha (N/m).
    const double alpha = s.stretch_compliance > 0 ? s.stretch_compliance : d / (s.youngs_modulus * kPi * rbar * rbar);
    adjacency_[std::size_t(e[0])].push_back({e[1], d, 1.0 / alpha});
    adjacency_[std::size_t(e[1])].push_back({e[0], d, 1.0 / alpha});
  }
}

std::size_t NodalRegion::interfaceCount() const {
  return std::size_t(std::count(role_.begin(), role_.end(), SphereRole::Interface));
}

double NodalRegion::pointMass() const {
  double m = 0.0;
  for (double v : mass_) m += v;
  return m;
}

void NodalRegion::syncState() {
  if (solver_) {
    solver_->displacements(u_);
    solver_->velocities(v_);
  }
}

std::size_t NodalRegion::convert(const std::vector<std::int32_t>& cut,
                                 const std::function<ConvertedSphereState(std::int32_t)>& state, const SweptSurface& stroke) {
  const std::size_t changed = beginConversion(cut, state);
  finishConversion(stroke);
  return changed;
}

std::size_t NodalRegion::beginConversion(const std::vector<std::int32_t>& cut,
                                         const std::function<ConvertedSphereState(std::int32_t)>& state) {
  last_rebuild_ms_ = 0.0;  // a conversion that samples no point rebuilds nothing
  times_ = ConversionTimes{};
  const auto t0 = std::chrono::steady_clock::now();
  syncState();
  std::size_t changed = 0;
  // The spheres converted now (cut ones not sampled yet, and new interface spheres), then their points.
  std::vector<std::int32_t> batch;
  for (std::int32_t b : cut) {
    if (role_[std::size_t(b)] == SphereRole::Cut) continue;
    if (sphere_points_[std::size_t(b)].empty()) batch.push_back(b);
    role_[std::size_t(b)] = SphereRole::Cut;
    ++changed;
  }
  for (std::int32_t b : cut)
    for (const Link& l : adjacency_[std::size_t(b)])
      if (role_[std::size_t(l.other)] == SphereRole::Pbd) {
        batch.push_back(l.other);
        role_[std::size_t(l.other)] = SphereRole::Interface;
        ++changed;
      }
  sample(batch, state);
  times_.sample_ms = msSince(t0);
  return changed;
}

void NodalRegion::finishConversion(const SweptSurface& stroke) {
  if (rest_.empty()) return;
  // Supports: symmetric lists of radius h with the visibility criterion for the stroke and every earlier cut,
  // updated for the new points and the stroke's new strip (a conversion's cost stays in what is new).
  const auto t0 = std::chrono::steady_clock::now();
  supports_.update(rest_, stroke);
  times_.supports_ms = msSince(t0);
  rebuild();
}

// Section 5.1's uniform sampling, on one lattice shared by every converted sphere (spacing 2 r_mean / n, cell
// centres): a cell inside the balls of spheres converted together goes to the one of least power distance
// |x - c|^2 - r^2, a cell taken earlier stays with its sphere, cells outside the tissue or hidden from the centre
// by an earlier cut are skipped; each sphere's mass is shared by its cells (its centre alone when it has none).
// One lattice rather than one per sphere: where balls overlap, per-sphere lattices interleave, and the MLS gradient
// does not see one sub-lattice sliding through the other, a zero-energy mode the coupling force (one sphere's
// points) excites (measured: points escaping by 11 cm in the flap test).
void NodalRegion::sample(const std::vector<std::int32_t>& batch, const std::function<ConvertedSphereState(std::int32_t)>& state) {
  const double p = spacing_;
  struct Candidate {
    std::int32_t sphere;
    double power;
  };
  // The candidate cells of every sphere of the batch (in the ball, not taken earlier), in batch order; their
  // inside and hidden tests (independent per cell and per candidate) in parallel; then the sequential choice.
  struct Trial {
    std::int32_t sphere;
    std::array<std::int64_t, 3> key;
    double power;
    char visible = 1;  // inside the tissue and seen from the sphere's centre
  };
  std::vector<Trial> trials;
  for (std::int32_t b : batch) {
    const Vec3d c = base_.rest_centers[std::size_t(b)];
    const double r = base_.rest_radii[std::size_t(b)];
    std::int64_t lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::int64_t(std::floor((c[k] - r) / p - 0.5));
      hi[k] = std::int64_t(std::ceil((c[k] + r) / p - 0.5));
    }
    for (std::int64_t i = lo[0]; i <= hi[0]; ++i)
      for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
        for (std::int64_t k = lo[2]; k <= hi[2]; ++k) {
          const std::array<std::int64_t, 3> key{i, j, k};
          if (occupied_.count(key)) continue;
          const Vec3d x((double(i) + 0.5) * p, (double(j) + 0.5) * p, (double(k) + 0.5) * p);
          const double power = norm2(x - c) - r * r;
          if (power < 0) trials.push_back({b, key, power});
        }
  }
  const auto centreOf = [p](const std::array<std::int64_t, 3>& key) {
    return Vec3d((double(key[0]) + 0.5) * p, (double(key[1]) + 0.5) * p, (double(key[2]) + 0.5) * p);
  };
  std::vector<SweptSurfaceQuery> earlier;  // segmentCrossesSweptSurface's decisions, triangles boxed once
  earlier.reserve(earlier_.size());
  for (const SweptSurface* c : earlier_) earlier.emplace_back(*c);
  cpu::parallelFor(std::int64_t(trials.size()), [&](std::int64_t t) {
    Trial& tr = trials[std::size_t(t)];
    const Vec3d x = centreOf(tr.key);
    if (settings_.inside && !settings_.inside(x)) {
      tr.visible = 0;
      return;
    }
    const Vec3d c = base_.rest_centers[std::size_t(tr.sphere)];
    for (const SweptSurfaceQuery& q : earlier)
      if (q.segmentCrosses(c, x)) {
        tr.visible = 0;
        return;
      }
  });
  // A cell goes to the visible candidate of least power, the first one on ties (the batch order).
  std::map<std::array<std::int64_t, 3>, Candidate> cells;  // ordered: deterministic
  for (const Trial& tr : trials) {
    if (!tr.visible) continue;
    auto it = cells.find(tr.key);
    if (it != cells.end() && !(tr.power < it->second.power)) continue;
    cells[tr.key] = {tr.sphere, tr.power};
  }
  std::map<std::int32_t, std::vector<Vec3d>> taken;
  for (const auto& [key, cand] : cells) {
    occupied_.insert(key);
    taken[cand.sphere].push_back(Vec3d((double(key[0]) + 0.5) * p, (double(key[1]) + 0.5) * p, (double(key[2]) + 0.5) * p));
  }
  for (std::int32_t b : batch) {
    std::vector<Vec3d>& pts = taken[b];
    const Vec3d c = base_.rest_centers[std::size_t(b)];
    if (pts.empty()) pts.push_back(c);
    const ConvertedSphereState st = state(b);
    bool fixed = false;
    for (const FixedRegion& f : settings_.fixed) fixed = fixed || insideBox(c, f);
    const double m = base_.masses[std::size_t(b)] / double(pts.size());  // section 5.1: m_i / n each
    for (const Vec3d& x : pts) {
      sphere_points_[std::size_t(b)].push_back(std::int32_t(rest_.size()));
      rest_.push_back(x);
      mass_.push_back(m);
      source_.push_back(b);
      kind_.push_back(fixed ? kMlsFixed : kMlsFree);
      u_.push_back(st.position + st.rotation * (x - c) - x);
      v_.push_back(fixed ? Vec3d() : st.velocity);
    }
  }
}

std::size_t NodalRegion::cutSupports(const SweptSurface& fresh) {
  if (rest_.empty() || fresh.empty()) return 0;
  const std::size_t removed = supports_.extend(rest_, fresh);
  if (removed == 0) return 0;
  syncState();
  rebuild();
  return removed;
}

// Groups: an interface sphere is one group (all its points) with a spring to each PBD-role link neighbour; a cut
// sphere has one group per connected piece of its points (supports among them), without springs.
void NodalRegion::regroup() {
  groups_ = MlsCouplingGroups{};
  group_sphere_.clear();
  spring_other_.clear();
  std::vector<std::int32_t> local(rest_.size(), -1);
  for (std::size_t b = 0; b < base_.size(); ++b) {
    const auto& pts = sphere_points_[b];
    if (pts.empty()) continue;
    std::vector<std::vector<std::int32_t>> pieces;
    if (role_[b] == SphereRole::Interface) {
      pieces.push_back(pts);
    } else {
      for (std::size_t k = 0; k < pts.size(); ++k) local[std::size_t(pts[k])] = std::int32_t(k);
      std::vector<std::int32_t> parent(pts.size());
      std::iota(parent.begin(), parent.end(), 0);
      const auto find = [&](std::int32_t a) {
        while (parent[std::size_t(a)] != a) a = parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];
        return a;
      };
      for (std::size_t k = 0; k < pts.size(); ++k)
        for (std::int64_t q = supports().offsets[std::size_t(pts[k])]; q < supports().offsets[std::size_t(pts[k]) + 1]; ++q) {
          const std::int32_t j = local[std::size_t(supports().indices[std::size_t(q)])];
          if (j < 0) continue;
          const std::int32_t a = find(std::int32_t(k)), c = find(j);
          if (a != c) parent[std::size_t(std::max(a, c))] = std::min(a, c);
        }
      std::vector<std::int32_t> slot(pts.size(), -1);
      for (std::size_t k = 0; k < pts.size(); ++k) {
        const std::int32_t r = find(std::int32_t(k));
        if (slot[std::size_t(r)] < 0) {
          slot[std::size_t(r)] = std::int32_t(pieces.size());
          pieces.emplace_back();
        }
        pieces[std::size_t(slot[std::size_t(r)])].push_back(pts[k]);
      }
      for (std::int32_t p : pts) local[std::size_t(p)] = -1;
    }
    for (const auto& piece : pieces) {
      groups_.members.insert(groups_.members.end(), piece.begin(), piece.end());
      groups_.member_offsets.push_back(std::int32_t(groups_.members.size()));
      groups_.rest_centres.push_back(base_.rest_centers[b]);
      if (role_[b] == SphereRole::Interface)
        for (const Link& l : adjacency_[b])
          if (role_[std::size_t(l.other)] == SphereRole::Pbd) {
            groups_.rest_lengths.push_back(l.rest);
            groups_.stiffnesses.push_back(l.stiffness);
            spring_other_.push_back(l.other);
          }
      groups_.spring_offsets.push_back(std::int32_t(groups_.rest_lengths.size()));
      group_sphere_.push_back(std::int32_t(b));
    }
  }
  group_u_.assign(groups_.size(), Vec3d());
  anchors_.assign(groups_.springs(), Vec3d());
}

void NodalRegion::rebuild() {
  const auto t0 = std::chrono::steady_clock::now();
  rebuildSolver();
  last_rebuild_ms_ = msSince(t0);
}

void NodalRegion::rebuildSolver() {
  regroup();
  MlsBuildInput in = settings_.mls;
  in.rest_positions = rest_;
  in.masses = mass_;
  in.kinds = kind_;
  in.spacing = spacing_;
  in.neighbors = supports();
  const auto t0 = std::chrono::steady_clock::now();
  rebuildMlsSolver(solver_, in, settings_.backend, settings_.precision, &times_.model_build_ms);  // the GPU reuses its buffers
  times_.model_ms = msSince(t0);
  const auto t1 = std::chrono::steady_clock::now();
  // A cut's few thousand points are launch-bound on the GPU: the substeps of an exchange replay as one graph.
  solver_->setStageTiming(false);
  solver_->setSafety(solver_->safety() * safety_scale_);
  solver_->setDisplacements(u_);
  solver_->setVelocities(v_);
  solver_->setCouplingGroups(groups_);
  // Anchors until the first exchange: each spring's PBD sphere where the points' own sphere puts it at rest
  // length along the rest direction (no force); the exchange replaces them with the PBD positions.
  solver_->couplingDisplacements(group_u_);
  for (std::size_t g = 0; g < groups_.size(); ++g)
    for (std::int32_t s = groups_.spring_offsets[g]; s < groups_.spring_offsets[g + 1]; ++s) {
      const std::int32_t j = spring_other_[std::size_t(s)];
      anchors_[std::size_t(s)] = base_.rest_centers[std::size_t(j)] + group_u_[g];
    }
  solver_->setCouplingAnchors(anchors_);
  last_reduction_ = solver_->reduce();
  times_.setup_ms = msSince(t1);
}

MlsFrameStats NodalRegion::advance(double dt, int fixed_substeps, const std::function<Vec3d(std::int32_t)>& pbd_position) {
  MlsFrameStats st;
  if (!solver_) return st;
  for (std::size_t s = 0; s < anchors_.size(); ++s) anchors_[s] = pbd_position(spring_other_[s]);
  solver_->setCouplingAnchors(anchors_);
  int n = 0;
  if (fixed_substeps > 0) {
    // At least the fixed count, more when the current stable step (deformation, springs) needs them.
    const double need = std::ceil(dt / (solver_->safety() * solver_->currentStableTimeStep()) * (1.0 - 1e-12));
    n = std::max(fixed_substeps, int(std::min(need, double(kMlsMaxSubsteps))));
  }
  solver_->setBladeContact(blade_from_.base, blade_from_.tip, blade_to_.base, blade_to_.tip, blade_radius_);
  st = solver_->advance(dt, n);
  last_reduction_ = st.totals;
  solver_->couplingDisplacements(group_u_);
  return st;
}

void NodalRegion::interfacePositions(std::vector<std::int32_t>& ids, std::vector<Vec3d>& pos) const {
  ids.clear();
  pos.clear();
  for (std::size_t g = 0; g < group_sphere_.size(); ++g) {
    const std::int32_t b = group_sphere_[g];
    if (role_[std::size_t(b)] != SphereRole::Interface) continue;
    ids.push_back(b);
    pos.push_back(base_.rest_centers[std::size_t(b)] + group_u_[g]);  // eq. 13
  }
}

bool NodalRegion::sphereDisplacement(std::int32_t b, const Vec3d& p, Vec3d& out) const {
  const auto& pts = sphere_points_[std::size_t(b)];
  if (pts.empty()) return false;
  // The point of b nearest p decides the piece; its group's eq. 13 displacement moves the skin.
  std::int32_t best = pts.front();
  double bd = norm2(rest_[std::size_t(best)] - p);
  for (std::int32_t q : pts) {
    const double d = norm2(rest_[std::size_t(q)] - p);
    if (d < bd) bd = d, best = q;
  }
  for (std::size_t g = 0; g < group_sphere_.size(); ++g) {
    if (group_sphere_[g] != b) continue;
    for (std::int32_t k = groups_.member_offsets[g]; k < groups_.member_offsets[g + 1]; ++k)
      if (groups_.members[std::size_t(k)] == best) {
        out = group_u_[g];
        return true;
      }
  }
  return false;
}

double NodalRegion::springEnergy() const {
  double e = 0.0;
  for (std::size_t g = 0; g < groups_.size(); ++g) {
    const Vec3d xa = groups_.rest_centres[g] + group_u_[g];
    for (std::int32_t s = groups_.spring_offsets[g]; s < groups_.spring_offsets[g + 1]; ++s)
      e += couplingSpringEnergy(xa, anchors_[std::size_t(s)], groups_.rest_lengths[std::size_t(s)],
                                groups_.stiffnesses[std::size_t(s)]);
  }
  return e;
}

void NodalRegion::saveCheckpoint() {
  if (solver_) solver_->saveCheckpoint();
}
void NodalRegion::restoreCheckpoint() {
  if (solver_) {
    solver_->restoreCheckpoint();
    solver_->couplingDisplacements(group_u_);
  }
}
void NodalRegion::scaleSafety(double factor) {
  if (!(factor > 0) || !std::isfinite(factor)) return;
  safety_scale_ *= factor;
  if (solver_) solver_->setSafety(solver_->safety() * factor);
}

RepackPoints NodalRegion::repackPoints() const {
  // The cut spheres' points to re-pack, the interface spheres' points as context (they stay: the faces the cut
  // points share with them are not the tissue's surface), and the supports among them all.
  RepackPoints p;
  p.rest = rest_;
  p.mass.resize(rest_.size());
  p.context.resize(rest_.size());
  for (std::size_t i = 0; i < rest_.size(); ++i) {
    const bool context = role_[std::size_t(source_[i])] != SphereRole::Cut;
    p.mass[i] = context ? 0.0 : mass_[i];
    p.context[i] = context ? 1 : 0;
  }
  p.visible = supports();
  p.spacing = spacing_;
  p.support = settings_.mls.support_factor * spacing_;
  return p;
}

NodalRegionFinal NodalRegion::finish(bool with_points) {
  NodalRegionFinal f;
  syncState();
  // Interface spheres: eq. 13 position and the mean velocity of their points.
  for (std::size_t g = 0; g < group_sphere_.size(); ++g) {
    const std::int32_t b = group_sphere_[g];
    if (role_[std::size_t(b)] != SphereRole::Interface) continue;
    Vec3d v;
    for (std::int32_t k = groups_.member_offsets[g]; k < groups_.member_offsets[g + 1]; ++k)
      v += v_[std::size_t(groups_.members[std::size_t(k)])];
    v *= 1.0 / double(groups_.member_offsets[g + 1] - groups_.member_offsets[g]);
    f.interface_ids.push_back(b);
    f.interface_position.push_back(base_.rest_centers[std::size_t(b)] + group_u_[g]);
    f.interface_velocity.push_back(v);
  }
  if (with_points) f.points = repackPoints();
  f.displacement = u_;
  f.velocity = v_;
  // The nodal points go back to zero between cuts.
  solver_.reset();
  rest_.clear();
  mass_.clear();
  source_.clear();
  kind_.clear();
  u_.clear();
  v_.clear();
  supports_.clear();
  groups_ = MlsCouplingGroups{};
  group_sphere_.clear();
  spring_other_.clear();
  group_u_.clear();
  anchors_.clear();
  for (auto& p : sphere_points_) p.clear();
  occupied_.clear();
  return f;
}

}  // namespace inc
