// NodalRegion: sphere -> points conversion during a stroke, visibility-filtered supports, MLS rebuilds, coupling
// groups.
#include "host/cut/cut_nodal_region.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>

#include "base/elapsed_ms.h"
#include "base/parallel.h"
#include "host/backends/solver_factory.h"
#include "host/compiled/material_checks.h"
#include "host/cut/cut_nodal_points.h"
#include "model/device_capture_lock.h"
#include "model/frame_budget.h"
#include "model/input_error.h"
#include "physics/cut_coupling.h"

namespace inc {

namespace {

const double kPi = 3.141592653589793;

bool insideBox(const Vec3d& p, const FixedRegion& r) {
  return p.x >= r.min.x && p.x <= r.max.x && p.y >= r.min.y && p.y <= r.max.y && p.z >= r.min.z && p.z <= r.max.z;
}

}  // namespace

NodalRegion::NodalRegion(const MetaballModel& base, const NodalRegionSettings& s,
                         std::vector<const SweptSurface*> earlier)
    : base_(base), settings_(s), earlier_(std::move(earlier)) {
  if (s.samples_per_diameter < 1 || s.samples_per_diameter > 64)
    throw InputError(s.mls.source, "cutting.samples_per_diameter", "must be in [1, 64]");
  if (s.backend == BackendKind::Auto)
    throw InputError(s.mls.source, "solver.backend", "the nodal region needs a resolved backend");
  validateMaterial(s.mls.material, s.mls.source);  // the links below divide by E
  r_.role.assign(base_.size(), SphereRole::Pbd);
  double rmean = 0.0;
  for (double r : base_.rest_radii) rmean += r / double(std::max<std::size_t>(1, base_.size()));
  spacing_ = 2.0 * rmean / s.samples_per_diameter;
  r_.supports = StrokeSupports(s.mls.support_factor * spacing_, earlier_);
  adjacency_.resize(base_.size());
  r_.sphere_points.resize(base_.size());
  for (std::size_t l = 0; l < base_.links.size(); ++l) {
    const auto& e = base_.links[l];
    const double d = base_.link_rest_lengths[l];
    const double rbar = 0.5 * (base_.rest_radii[std::size_t(e[0])] + base_.rest_radii[std::size_t(e[1])]);
    // The PBD link's compliance (host/assembly/pbd_builders.cpp) as a Hooke spring: k = 1 / alpha (N/m).
    const double alpha =
        s.stretch_compliance > 0 ? s.stretch_compliance : d / (s.mls.material.youngs_modulus_pa * kPi * rbar * rbar);
    adjacency_[std::size_t(e[0])].push_back({e[1], d, 1.0 / alpha});
    adjacency_[std::size_t(e[1])].push_back({e[0], d, 1.0 / alpha});
  }
}

std::size_t NodalRegion::interfaceCount() const {
  return std::size_t(std::count(r_.role.begin(), r_.role.end(), SphereRole::Interface));
}

double NodalRegion::pointMass() const {
  double m = 0.0;
  for (double v : r_.mass) m += v;
  return m;
}

void NodalRegion::syncState() {
  if (solver_) {
    solver_->displacements(u_);
    solver_->velocities(v_);
  }
}

std::vector<SphereRole> NodalRegion::rolesAfter(const std::vector<std::int32_t>& cut) const {
  std::vector<SphereRole> role = r_.role;
  for (std::int32_t b : cut) role[std::size_t(b)] = SphereRole::Cut;
  for (std::int32_t b : cut)
    for (const Link& l : adjacency_[std::size_t(b)])
      if (role[std::size_t(l.other)] == SphereRole::Pbd) role[std::size_t(l.other)] = SphereRole::Interface;
  return role;
}

NodalUpdate NodalRegion::prepareConversion(NodalRest from, const std::vector<std::int32_t>& cut,
                                           const SweptSurface& stroke) const {
  NodalUpdate u;
  u.next = std::move(from);
  NodalRest& r = u.next;
  u.first_new = r.rest.size();
  const auto t0 = std::chrono::steady_clock::now();
  // The spheres converted now (cut ones not sampled yet, and new interface spheres), then their points.
  for (std::int32_t b : cut) {
    if (r.role[std::size_t(b)] == SphereRole::Cut) continue;
    if (r.sphere_points[std::size_t(b)].empty()) u.sampled.push_back(b);
    r.role[std::size_t(b)] = SphereRole::Cut;
    ++u.changed;
  }
  for (std::int32_t b : cut)
    for (const Link& l : adjacency_[std::size_t(b)])
      if (r.role[std::size_t(l.other)] == SphereRole::Pbd) {
        u.sampled.push_back(l.other);
        r.role[std::size_t(l.other)] = SphereRole::Interface;
        ++u.changed;
      }
  sample(r, u.sampled);
  u.sample_ms = msSince(t0);
  if (r.rest.empty()) return u;  // nothing sampled: nothing to rebuild
  // Supports: symmetric lists of radius h with the visibility criterion for the stroke and every earlier cut,
  // updated for the new points and the stroke's new strip (a conversion's cost stays in what is new).
  const auto t1 = std::chrono::steady_clock::now();
  r.supports.update(r.rest, stroke);
  u.supports_ms = msSince(t1);
  build(u);
  return u;
}

NodalUpdate NodalRegion::prepareStrip(NodalRest from, const SweptSurface& fresh) const {
  NodalUpdate u;
  u.next = std::move(from);
  u.first_new = u.next.rest.size();
  if (u.next.rest.empty() || fresh.empty()) return u;
  const auto t0 = std::chrono::steady_clock::now();
  u.removed = u.next.supports.extend(u.next.rest, fresh);
  u.supports_ms = msSince(t0);
  if (u.removed > 0) build(u);
  return u;
}

void NodalRegion::build(NodalUpdate& u) const {
  regroup(u.next);
  MlsBuildInput in = settings_.mls;
  in.rest_positions = u.next.rest;
  in.masses = u.next.mass;
  in.kinds = u.next.kind;
  in.spacing = spacing_;
  in.neighbors = u.next.supports.lists();
  const auto t0 = std::chrono::steady_clock::now();
  u.model = buildMlsModelIn(in, settings_.precision);
  u.model_build_ms = msSince(t0);
  u.rebuild = true;
}

void NodalRegion::apply(NodalUpdate& u, const std::vector<ConvertedSphereState>& sampled_state) {
  if (sampled_state.size() != u.sampled.size())
    throw std::logic_error("NodalRegion::apply: one state per sampled sphere is needed");
  last_rebuild_ms_ = 0.0;
  times_ = ConversionTimes{};
  times_.sample_ms = u.sample_ms;
  times_.supports_ms = u.supports_ms;
  times_.model_build_ms = u.model_build_ms;
  if (!u.rebuild) {  // a strip that dropped no support, or nothing sampled: the points and their state stay
    r_ = std::move(u.next);
    return;
  }
  syncState();
  // The new points start rigidly attached to their sphere: x = x_b + R_b (X - C_b), v = v_b.
  const NodalRest& r = u.next;
  for (std::size_t k = 0; k < u.sampled.size(); ++k) {
    const std::int32_t b = u.sampled[k];
    const ConvertedSphereState& st = sampled_state[k];
    const Vec3d c = base_.rest_centers[std::size_t(b)];
    for (std::int32_t i : r.sphere_points[std::size_t(b)]) {
      if (std::size_t(i) < u.first_new) continue;
      const Vec3d x = r.rest[std::size_t(i)];
      u_.push_back(st.position + st.rotation * (x - c) - x);
      v_.push_back(r.kind[std::size_t(i)] == kMlsFixed ? Vec3d() : st.velocity);
    }
  }
  r_ = std::move(u.next);
  const auto t0 = std::chrono::steady_clock::now();
  if (u.preloaded) {  // loaded on a worker: the current solver becomes the next spare
    spare_ = std::move(solver_);
    solver_ = std::move(u.preloaded);
  } else {
    loadMlsSolver(solver_, u.model, settings_.backend);  // the GPU reuses its buffers
    loadRestData(*solver_, r_.groups);
  }
  times_.model_ms = u.model_build_ms + msSince(t0);
  const auto t1 = std::chrono::steady_clock::now();
  solver_->setSafety(solver_->safety() * safety_scale_);
  solver_->setDisplacements(u_);
  solver_->setVelocities(v_);
  // Anchors until the first exchange: each spring's PBD sphere where the points' own sphere puts it at rest
  // length along the rest direction (no force); the exchange replaces them with the PBD positions.
  group_u_.assign(r_.groups.size(), Vec3d());
  anchors_.assign(r_.groups.springs(), Vec3d());
  solver_->couplingDisplacements(group_u_);
  for (std::size_t g = 0; g < r_.groups.size(); ++g)
    for (std::int32_t s = r_.groups.spring_offsets[g]; s < r_.groups.spring_offsets[g + 1]; ++s) {
      const std::int32_t j = r_.spring_other[std::size_t(s)];
      anchors_[std::size_t(s)] = base_.rest_centers[std::size_t(j)] + group_u_[g];
    }
  solver_->setCouplingAnchors(anchors_);
  last_reduction_ = solver_->reduce();
  times_.setup_ms = msSince(t1);
  last_rebuild_ms_ = msSince(t0);
}

// What a solver takes from the rest data beside its model. A cut's few thousand points are launch-bound on the GPU:
// the substeps of an exchange run untimed (one graph, or one cooperative launch).
void NodalRegion::loadRestData(MlsSolver& s, const MlsCouplingGroups& groups) const {
  s.setStageTiming(false);
  s.setStaticColliders(settings_.colliders.planes, settings_.colliders.boxes, 0.5 * spacing_);
  s.setCouplingGroups(groups);
}

void NodalRegion::preload(NodalUpdate& u) {
  if (!u.rebuild) return;
  const std::lock_guard<std::mutex> lock(deviceCaptureMutex());
  std::unique_ptr<MlsSolver> s = std::move(spare_);
  loadMlsSolver(s, u.model, settings_.backend);
  loadRestData(*s, u.next.groups);
  u.preloaded = std::move(s);
}

std::size_t NodalRegion::convert(const std::vector<std::int32_t>& cut,
                                 const std::function<ConvertedSphereState(std::int32_t)>& state,
                                 const SweptSurface& stroke) {
  NodalUpdate u = prepareConversion(takeRest(), cut, stroke);
  std::vector<ConvertedSphereState> st;
  for (std::int32_t b : u.sampled) st.push_back(state(b));
  apply(u, st);
  return u.changed;
}

std::size_t NodalRegion::cutSupports(const SweptSurface& fresh) {
  NodalUpdate u = prepareStrip(takeRest(), fresh);
  apply(u, {});
  return u.removed;
}

// Section 5.1's uniform sampling, on one lattice shared by every converted sphere (spacing 2 r_mean / n, cell
// centres): a cell inside the balls of spheres converted together goes to the one of least power distance
// |x - c|^2 - r^2, a cell taken earlier stays with its sphere, cells outside the tissue or hidden from the centre
// by an earlier cut are skipped; each sphere's mass is shared by its cells (its centre alone when it has none).
// One lattice rather than one per sphere: where balls overlap, per-sphere lattices interleave, and the MLS gradient
// does not see one sub-lattice sliding through the other, a zero-energy mode the coupling force (one sphere's
// points) excites (measured: points escaping by 11 cm in the flap test).
void NodalRegion::sample(NodalRest& next, const std::vector<std::int32_t>& batch) const {
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
          if (next.occupied.count(key)) continue;
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
    next.occupied.insert(key);
    taken[cand.sphere].push_back(
        Vec3d((double(key[0]) + 0.5) * p, (double(key[1]) + 0.5) * p, (double(key[2]) + 0.5) * p));
  }
  for (std::int32_t b : batch) {
    std::vector<Vec3d>& pts = taken[b];
    const Vec3d c = base_.rest_centers[std::size_t(b)];
    if (pts.empty()) pts.push_back(c);
    bool fixed = false;
    for (const FixedRegion& f : settings_.fixed) fixed = fixed || insideBox(c, f);
    const double m = base_.masses[std::size_t(b)] / double(pts.size());  // section 5.1: m_i / n each
    for (const Vec3d& x : pts) {
      next.sphere_points[std::size_t(b)].push_back(std::int32_t(next.rest.size()));
      next.rest.push_back(x);
      next.mass.push_back(m);
      next.source.push_back(b);
      next.kind.push_back(fixed ? kMlsFixed : kMlsFree);
    }
  }
}

// Groups: an interface sphere is one group (all its points) with a spring to each PBD-role link neighbour; a cut
// sphere has one group per connected piece of its points (supports among them), without springs.
void NodalRegion::regroup(NodalRest& r) const {
  r.groups = MlsCouplingGroups{};
  r.group_sphere.clear();
  r.spring_other.clear();
  std::vector<std::int32_t> local(r.rest.size(), -1);
  for (std::size_t b = 0; b < base_.size(); ++b) {
    const auto& pts = r.sphere_points[b];
    if (pts.empty()) continue;
    std::vector<std::vector<std::int32_t>> pieces;
    if (r.role[b] == SphereRole::Interface) {
      pieces.push_back(pts);
    } else {
      for (std::size_t k = 0; k < pts.size(); ++k) local[std::size_t(pts[k])] = std::int32_t(k);
      std::vector<std::int32_t> parent(pts.size());
      std::iota(parent.begin(), parent.end(), 0);
      const auto find = [&](std::int32_t a) {
        while (parent[std::size_t(a)] != a) a = parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];
        return a;
      };
      const NeighborLists& sup = r.supports.lists();
      for (std::size_t k = 0; k < pts.size(); ++k)
        for (std::int64_t q = sup.offsets[std::size_t(pts[k])]; q < sup.offsets[std::size_t(pts[k]) + 1]; ++q) {
          const std::int32_t j = local[std::size_t(sup.indices[std::size_t(q)])];
          if (j < 0) continue;
          const std::int32_t a = find(std::int32_t(k)), c = find(j);
          if (a != c) parent[std::size_t(std::max(a, c))] = std::min(a, c);
        }
      std::vector<std::int32_t> slot(pts.size(), -1);
      for (std::size_t k = 0; k < pts.size(); ++k) {
        const std::int32_t root = find(std::int32_t(k));
        if (slot[std::size_t(root)] < 0) {
          slot[std::size_t(root)] = std::int32_t(pieces.size());
          pieces.emplace_back();
        }
        pieces[std::size_t(slot[std::size_t(root)])].push_back(pts[k]);
      }
      for (std::int32_t p : pts) local[std::size_t(p)] = -1;
    }
    for (const auto& piece : pieces) {
      r.groups.members.insert(r.groups.members.end(), piece.begin(), piece.end());
      r.groups.member_offsets.push_back(std::int32_t(r.groups.members.size()));
      r.groups.rest_centres.push_back(base_.rest_centers[b]);
      if (r.role[b] == SphereRole::Interface)
        for (const Link& l : adjacency_[b])
          if (r.role[std::size_t(l.other)] == SphereRole::Pbd) {
            r.groups.rest_lengths.push_back(l.rest);
            r.groups.stiffnesses.push_back(l.stiffness);
            r.spring_other.push_back(l.other);
          }
      r.groups.spring_offsets.push_back(std::int32_t(r.groups.rest_lengths.size()));
      r.group_sphere.push_back(std::int32_t(b));
    }
  }
}

MlsFrameStats NodalRegion::advance(double dt, int fixed_substeps,
                                   const std::function<Vec3d(std::int32_t)>& pbd_position) {
  MlsFrameStats st;
  if (!solver_) return st;
  for (std::size_t s = 0; s < anchors_.size(); ++s) anchors_[s] = pbd_position(r_.spring_other[s]);
  solver_->setCouplingAnchors(anchors_);
  solver_->setMaxSubsteps(substepLimit());
  int n = 0;
  if (fixed_substeps > 0) {
    // At least the fixed count, more when the current stable step (deformation, springs) needs them; beyond the
    // limit the solver refuses the exchange.
    const double need = std::ceil(dt / (solver_->safety() * solver_->currentStableTimeStep()) * (1.0 - 1e-12));
    n = std::max(fixed_substeps, int(std::min(need, 2.0e9)));
  }
  solver_->setBladeContact(blade_from_.base, blade_from_.tip, blade_to_.base, blade_to_.tip, blade_radius_,
                           blade_friction_);
  st = solver_->advanceCoupled(dt, n, group_u_);
  last_reduction_ = st.totals;
  return st;
}

void NodalRegion::interfacePositions(std::vector<std::int32_t>& ids, std::vector<Vec3d>& pos) const {
  ids.clear();
  pos.clear();
  for (std::size_t g = 0; g < r_.group_sphere.size(); ++g) {
    const std::int32_t b = r_.group_sphere[g];
    if (r_.role[std::size_t(b)] != SphereRole::Interface) continue;
    ids.push_back(b);
    pos.push_back(base_.rest_centers[std::size_t(b)] + group_u_[g]);  // eq. 13
  }
}

bool NodalRegion::sphereDisplacement(std::int32_t b, const Vec3d& p, Vec3d& out) const {
  const auto& pts = r_.sphere_points[std::size_t(b)];
  if (pts.empty()) return false;
  // The point of b nearest p decides the piece; its group's eq. 13 displacement moves the skin.
  std::int32_t best = pts.front();
  double bd = norm2(r_.rest[std::size_t(best)] - p);
  for (std::int32_t q : pts) {
    const double d = norm2(r_.rest[std::size_t(q)] - p);
    if (d < bd) bd = d, best = q;
  }
  for (std::size_t g = 0; g < r_.group_sphere.size(); ++g) {
    if (r_.group_sphere[g] != b) continue;
    for (std::int32_t k = r_.groups.member_offsets[g]; k < r_.groups.member_offsets[g + 1]; ++k)
      if (r_.groups.members[std::size_t(k)] == best) {
        out = group_u_[g];
        return true;
      }
  }
  return false;
}

double NodalRegion::springEnergy() const {
  double e = 0.0;
  for (std::size_t g = 0; g < r_.groups.size(); ++g) {
    const Vec3d xa = r_.groups.rest_centres[g] + group_u_[g];
    for (std::int32_t s = r_.groups.spring_offsets[g]; s < r_.groups.spring_offsets[g + 1]; ++s)
      e += couplingSpringEnergy(xa, anchors_[std::size_t(s)], r_.groups.rest_lengths[std::size_t(s)],
                                r_.groups.stiffnesses[std::size_t(s)]);
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
int NodalRegion::substepLimit() const {
  const int frame = frameSubstepLimit(r_.rest.size(), settings_.max_substeps);
  const int k = std::max(1, settings_.exchanges_per_frame);
  return std::max(1, (frame + k - 1) / k);
}

std::string NodalRegion::substepLimitRule() const {
  std::string rule = frameSubstepLimitRule(r_.rest.size(), settings_.max_substeps);
  if (settings_.exchanges_per_frame > 1)
    rule += "; shared by cutting.exchanges_per_frame = " + std::to_string(settings_.exchanges_per_frame) + " exchanges";
  return rule;
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
  p.rest = r_.rest;
  p.mass.resize(r_.rest.size());
  p.context.resize(r_.rest.size());
  for (std::size_t i = 0; i < r_.rest.size(); ++i) {
    const bool context = r_.role[std::size_t(r_.source[i])] != SphereRole::Cut;
    p.mass[i] = context ? 0.0 : r_.mass[i];
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
  for (std::size_t g = 0; g < r_.group_sphere.size(); ++g) {
    const std::int32_t b = r_.group_sphere[g];
    if (r_.role[std::size_t(b)] != SphereRole::Interface) continue;
    Vec3d v;
    for (std::int32_t k = r_.groups.member_offsets[g]; k < r_.groups.member_offsets[g + 1]; ++k)
      v += v_[std::size_t(r_.groups.members[std::size_t(k)])];
    v *= 1.0 / double(r_.groups.member_offsets[g + 1] - r_.groups.member_offsets[g]);
    f.interface_ids.push_back(b);
    f.interface_position.push_back(base_.rest_centers[std::size_t(b)] + group_u_[g]);
    f.interface_velocity.push_back(v);
  }
  if (with_points) f.points = repackPoints();
  f.displacement = u_;
  f.velocity = v_;
  // The nodal points go back to zero between cuts (the roles stay: the stroke's end reads them).
  solver_.reset();
  u_.clear();
  v_.clear();
  group_u_.clear();
  anchors_.clear();
  NodalRest empty;
  empty.role = std::move(r_.role);
  empty.sphere_points.resize(r_.sphere_points.size());
  empty.supports = std::move(r_.supports);
  empty.supports.clear();
  r_ = std::move(empty);
  return f;
}

}  // namespace inc
