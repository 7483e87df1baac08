// Builds PBD constraint blocks for metaball organs and triangle sheets, with material-derived compliances.
#include "host/assembly/pbd_builders.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "host/compiled/material_checks.h"
#include "host/compiled/scene_colliders.h"
#include "model/input_error.h"
#include "physics/pbd_constraints.h"

namespace inc {

namespace {
const double kPi = 3.141592653589793;

void validateMetaballs(const MetaballModel& mb) {
  const char* f = "metaball model";
  const std::size_t n = mb.size();
  if (n == 0) throw InputError(f, "rest_centers", "no spheres");
  if (mb.rest_radii.size() != n || mb.masses.size() != n)
    throw InputError(f, "rest_radii/masses", "need one radius and one mass per sphere");
  if (mb.link_rest_lengths.size() != mb.links.size())
    throw InputError(f, "link_rest_lengths", "need one rest length per link");
  // The keys are spelled out only on failure: a cut rebuilds the model every frame the blade enters spheres.
  const auto at = [](const char* key, std::size_t i) { return std::string(key) + "[" + std::to_string(i) + "]"; };
  for (std::size_t i = 0; i < n; ++i) {
    if (!isFinite(mb.rest_centers[i])) throw InputError(f, at("rest_centers", i), "not finite");
    if (!(mb.rest_radii[i] > 0) || !std::isfinite(mb.rest_radii[i]))
      throw InputError(f, at("rest_radii", i), "must be > 0");
    if (!(mb.masses[i] > 0) || !std::isfinite(mb.masses[i])) throw InputError(f, at("masses", i), "must be > 0");
  }
  std::vector<std::pair<int, int>> seen;
  seen.reserve(mb.links.size());
  for (std::size_t l = 0; l < mb.links.size(); ++l) {
    const auto& e = mb.links[l];
    if (e[0] < 0 || e[1] < 0 || std::size_t(e[0]) >= n || std::size_t(e[1]) >= n)
      throw InputError(f, at("links", l), "index out of range");
    if (e[0] == e[1]) throw InputError(f, at("links", l), "links a sphere to itself");
    if (!(mb.link_rest_lengths[l] > 0) || !std::isfinite(mb.link_rest_lengths[l]))
      throw InputError(f, at("link_rest_lengths", l), "must be > 0");
    seen.emplace_back(std::min(e[0], e[1]), std::max(e[0], e[1]));
  }
  std::sort(seen.begin(), seen.end());
  if (std::adjacent_find(seen.begin(), seen.end()) != seen.end()) throw InputError(f, "links", "duplicate link");
}

bool insideBox(const Vec3d& p, const FixedRegion& r) {
  return p.x >= r.min.x && p.x <= r.max.x && p.y >= r.min.y && p.y <= r.max.y && p.z >= r.min.z && p.z <= r.max.z;
}

void validateMetaballOptions(const MetaballPbdOptions& opt) {
  const char* f = "metaball options";
  validateYoungsModulus(opt.youngs_modulus_pa, opt.file);  // host/compiled/material_checks.h
  if (opt.stretch_compliance < 0 || opt.laplacian_compliance < 0 || opt.shape_compliance < 0)
    throw InputError(f, "compliance", "must be >= 0");
  if (!(opt.pbd_stiffness >= 0 && opt.pbd_stiffness <= 1)) throw InputError(f, "pbd_stiffness", "must be in [0, 1]");
  if (opt.volume_samples != 0 && opt.volume_samples < 8) throw InputError(f, "volume_samples", "0 or >= 8");
}

// One particle per sphere; a sphere whose centre lies in a fixed box gets zero inverse mass.
template <typename T>
void setSphereParticles(PbdModel<T>& m, const MetaballModel& mb, const std::vector<FixedRegion>& fixed_regions) {
  const std::size_t n = mb.size();
  m.rest_positions.resize(n);
  m.masses.resize(n);
  m.inv_mass.resize(n);
  m.rest_radii.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    m.rest_positions[i] = Vec3<T>(mb.rest_centers[i]);
    m.masses[i] = T(mb.masses[i]);
    m.rest_radii[i] = T(mb.rest_radii[i]);
    bool fixed = false;
    for (const FixedRegion& r : fixed_regions) fixed = fixed || insideBox(mb.rest_centers[i], r);
    m.inv_mass[i] = fixed ? T(0) : T(1.0 / mb.masses[i]);
  }
}

// A support that holds nothing lets the organ fall: say so instead (a coarse packing can leave a thin
// clamp box between sphere centres).
void requireFixedBoxesHoldSpheres(const MetaballModel& mb, const MetaballPbdOptions& opt) {
  const std::size_t n = mb.size();
  for (std::size_t k = 0; opt.require_fixed_held && k < opt.fixed.size(); ++k) {
    double nearest = 1e300;
    bool held = false;
    for (std::size_t i = 0; i < n && !held; ++i) {
      held = insideBox(mb.rest_centers[i], opt.fixed[k]);
      const Vec3d c = mb.rest_centers[i];
      const Vec3d q(std::clamp(c.x, opt.fixed[k].min.x, opt.fixed[k].max.x),
                    std::clamp(c.y, opt.fixed[k].min.y, opt.fixed[k].max.y),
                    std::clamp(c.z, opt.fixed[k].min.z, opt.fixed[k].max.z));
      nearest = std::min(nearest, norm(c - q));
    }
    if (!held && n > 0)
      throw InputError(opt.file, "fixed[" + std::to_string(k) + "]",
                       "the box holds no sphere centre (the nearest is " + std::to_string(nearest * 1e3) +
                           " mm outside); enlarge it or use more spheres");
  }
}

// Neighbour lists from the links (ascending).
std::vector<std::vector<std::int32_t>> linkNeighbors(const MetaballModel& mb) {
  std::vector<std::vector<std::int32_t>> nbr(mb.size());
  for (const auto& e : mb.links) {
    nbr[e[0]].push_back(e[1]);
    nbr[e[1]].push_back(e[0]);
  }
  for (auto& l : nbr) std::sort(l.begin(), l.end());
  return nbr;
}

// Shape-matching clusters {i} u N(i) (solved first: it updates the rotations the Laplacian uses).
template <typename T>
PbdConstraintBlock<T> shapeMatchingBlock(const MetaballModel& mb, const std::vector<std::vector<std::int32_t>>& nbr,
                                         const MetaballPbdOptions& opt) {
  const std::size_t n = mb.size();
  const double E = opt.youngs_modulus_pa;
  PbdConstraintBlock<T> shape;
  shape.kind = PbdConstraintKind::ShapeMatching;
  shape.solve = opt.shape_matching;
  shape.stiffness = T(opt.pbd_stiffness);
  shape.ids.reserve(n + 2 * mb.links.size());
  shape.rest_vec.reserve(n + 2 * mb.links.size());
  shape.compliance.reserve(n + 2 * mb.links.size());
  shape.offsets.reserve(n + 1);
  std::vector<std::int32_t> members;
  for (std::size_t i = 0; i < n; ++i) {
    members.assign(1, std::int32_t(i));
    members.insert(members.end(), nbr[i].begin(), nbr[i].end());
    Vec3d cm;
    double msum = 0;
    for (std::int32_t j : members) {
      cm += mb.rest_centers[j] * mb.masses[j];
      msum += mb.masses[j];
    }
    cm *= 1.0 / msum;
    for (std::int32_t j : members) {
      shape.ids.push_back(j);
      shape.rest_vec.push_back(Vec3<T>(mb.rest_centers[j] - cm));
      const double nj = double(nbr[j].size() + 1);
      shape.compliance.push_back(T(opt.shape_compliance > 0 ? opt.shape_compliance : nj / (E * mb.rest_radii[j])));
    }
    shape.offsets.push_back(std::int32_t(shape.ids.size()));
  }
  return shape;
}

// Laplacian coordinates: each sphere's offset from the mean of its neighbours.
template <typename T>
PbdConstraintBlock<T> laplacianBlock(const MetaballModel& mb, const std::vector<std::vector<std::int32_t>>& nbr,
                                     const MetaballPbdOptions& opt) {
  const double E = opt.youngs_modulus_pa;
  PbdConstraintBlock<T> lap;
  lap.kind = PbdConstraintKind::Laplacian;
  lap.stiffness = T(opt.pbd_stiffness);
  for (std::size_t i = 0; i < mb.size(); ++i) {
    if (nbr[i].empty()) continue;
    Vec3d mean;
    for (std::int32_t j : nbr[i]) mean += mb.rest_centers[j];
    mean *= 1.0 / double(nbr[i].size());
    lap.ids.push_back(std::int32_t(i));
    lap.ids.insert(lap.ids.end(), nbr[i].begin(), nbr[i].end());
    lap.offsets.push_back(std::int32_t(lap.ids.size()));
    lap.rest_vec.push_back(Vec3<T>(mb.rest_centers[i] - mean));
    lap.compliance.push_back(T(opt.laplacian_compliance > 0 ? opt.laplacian_compliance : 1.0 / (E * mb.rest_radii[i])));
  }
  return lap;
}

// One distance constraint per link; the default compliance is that of a rod of the mean radius.
template <typename T>
PbdConstraintBlock<T> linkDistanceBlock(const MetaballModel& mb, const MetaballPbdOptions& opt) {
  const double E = opt.youngs_modulus_pa;
  PbdConstraintBlock<T> dist;
  dist.kind = PbdConstraintKind::Distance;
  dist.stiffness = T(opt.pbd_stiffness);
  for (std::size_t l = 0; l < mb.links.size(); ++l) {
    const auto& e = mb.links[l];
    dist.ids.push_back(e[0]);
    dist.ids.push_back(e[1]);
    dist.offsets.push_back(std::int32_t(dist.ids.size()));
    const double d = mb.link_rest_lengths[l];
    dist.rest.push_back(T(d));
    const double rbar = 0.5 * (mb.rest_radii[e[0]] + mb.rest_radii[e[1]]);
    dist.compliance.push_back(T(opt.stretch_compliance > 0 ? opt.stretch_compliance : d / (E * kPi * rbar * rbar)));
  }
  return dist;
}

// Volume preservation: linked spheres are the overlapping ones.
template <typename T>
void setOverlapsFromLinks(PbdModel<T>& m, const std::vector<std::vector<std::int32_t>>& nbr) {
  m.overlap_offsets.assign(1, 0);
  for (const auto& l : nbr) {
    m.overlap_ids.insert(m.overlap_ids.end(), l.begin(), l.end());
    m.overlap_offsets.push_back(std::int32_t(m.overlap_ids.size()));
  }
}

// The scene's static colliders, and how deep inside each sphere they meet the organ's surface.
template <typename T>
void setStaticContacts(PbdModel<T>& m, const MetaballModel& mb, const MetaballPbdOptions& opt) {
  const std::size_t n = mb.size();
  const StaticColliders colliders = staticColliders(opt.colliders);
  for (const auto& p : colliders.planes) m.planes.push_back({Vec3<T>(p.normal), T(p.offset), T(p.friction)});
  for (const auto& b : colliders.boxes) m.boxes.push_back({Vec3<T>(b.min), Vec3<T>(b.max), T(b.friction)});
  // Where a ball bulges beyond the organ's surface (by up to a quarter lattice spacing on flat faces, more on curved
  // ones) the static colliders meet the surface: inset = radius - depth of the centre, clamped to [0, radius].
  if (!opt.known_contact_insets.empty() && opt.known_contact_insets.size() != n)
    throw InputError("metaball options", "known_contact_insets", "must hold one entry per sphere (or none)");
  if (!opt.colliders.empty() && opt.surface_depth) {
    m.contact_inset.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      if (!opt.known_contact_insets.empty() && !std::isnan(opt.known_contact_insets[i])) {
        m.contact_inset[i] = T(opt.known_contact_insets[i]);
        continue;
      }
      const double depth = std::max(0.0, opt.surface_depth(mb.rest_centers[i]));
      m.contact_inset[i] = T(std::min(mb.rest_radii[i], std::max(0.0, mb.rest_radii[i] - depth)));
    }
  }
}

}  // namespace

template <typename T>
PbdModel<T> buildMetaballPbdModel(const MetaballModel& mb, const MetaballPbdOptions& opt) {
  validateMetaballs(mb);
  validateMetaballOptions(opt);
  PbdModel<T> m;
  setSphereParticles(m, mb, opt.fixed);
  requireFixedBoxesHoldSpheres(mb, opt);
  const std::vector<std::vector<std::int32_t>> nbr = linkNeighbors(mb);
  m.blocks.push_back(shapeMatchingBlock<T>(mb, nbr, opt));
  m.rotation_block = 0;
  if (opt.laplacian) m.blocks.push_back(laplacianBlock<T>(mb, nbr, opt));
  m.blocks.push_back(linkDistanceBlock<T>(mb, opt));
  setOverlapsFromLinks(m, nbr);
  setStaticContacts(m, mb, opt);
  finalizePbdModel(m, opt.coloring);
  if (!opt.known_cell_volumes.empty() && opt.known_cell_volumes.size() != mb.size())
    throw InputError("metaball options", "known_cell_volumes", "must hold one entry per sphere (or none)");
  if (opt.volume_samples > 0)
    computeRestCellVolumes(m, opt.volume_samples, opt.known_cell_volumes.empty() ? nullptr : &opt.known_cell_volumes);
  return m;
}

MetaballModel makeLatticeMetaballs(const Vec3d& lo, const Vec3d& hi, double spacing, double radius_factor,
                                   double density) {
  const char* f = "lattice";
  if (!(spacing > 0) || !(radius_factor > 0) || !(density > 0))
    throw InputError(f, "spacing", "parameters must be > 0");
  int cells[3];
  for (int k = 0; k < 3; ++k) {
    if (!(hi[k] >= lo[k])) throw InputError(f, "bounds", "hi must be >= lo");
    cells[k] = int(std::floor((hi[k] - lo[k]) / spacing + 1e-9)) + 1;
  }
  if (double(cells[0]) * cells[1] * cells[2] > 5.0e7) throw InputError(f, "spacing", "too many spheres");
  MetaballModel mb;
  const double r = radius_factor * spacing;
  for (int i = 0; i < cells[0]; ++i)
    for (int j = 0; j < cells[1]; ++j)
      for (int k = 0; k < cells[2]; ++k) {
        mb.rest_centers.push_back(lo + Vec3d(i * spacing, j * spacing, k * spacing));
        mb.rest_radii.push_back(r);
        mb.masses.push_back(density * spacing * spacing * spacing);
      }
  auto index = [&](int i, int j, int k) { return std::int32_t((i * cells[1] + j) * cells[2] + k); };
  // Lattice neighbours within the overlap distance 2r (offsets up to 2 cells cover radius_factor < 1).
  const int reach = int(std::ceil(2.0 * radius_factor));
  for (int i = 0; i < cells[0]; ++i)
    for (int j = 0; j < cells[1]; ++j)
      for (int k = 0; k < cells[2]; ++k)
        for (int di = -reach; di <= reach; ++di)
          for (int dj = -reach; dj <= reach; ++dj)
            for (int dk = -reach; dk <= reach; ++dk) {
              const int a = i + di, b = j + dj, c = k + dk;
              if (a < 0 || b < 0 || c < 0 || a >= cells[0] || b >= cells[1] || c >= cells[2]) continue;
              const std::int32_t p = index(i, j, k), q = index(a, b, c);
              if (q <= p) continue;
              const double d = spacing * std::sqrt(double(di * di + dj * dj + dk * dk));
              if (d < 2.0 * r) {
                mb.links.push_back({p, q});
                mb.link_rest_lengths.push_back(d);
              }
            }
  return mb;
}

template <typename T>
PbdModel<T> buildSheetPbdModel(const std::vector<Vec3d>& vertices,
                               const std::vector<std::array<std::int32_t, 3>>& triangles,
                               const std::vector<double>& masses, const SheetPbdOptions& opt) {
  const char* f = "sheet";
  const std::size_t n = vertices.size();
  if (masses.size() != n) throw InputError(f, "masses", "one mass per vertex");
  if (opt.stretch_compliance < 0 || opt.bending_compliance < 0) throw InputError(f, "compliance", "must be >= 0");
  PbdModel<T> m;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(masses[i] > 0)) throw InputError(f, "masses[" + std::to_string(i) + "]", "must be > 0");
    m.rest_positions.push_back(Vec3<T>(vertices[i]));
    m.masses.push_back(T(masses[i]));
    m.inv_mass.push_back(T(1.0 / masses[i]));
    m.rest_radii.push_back(T(0));
  }
  // edge (a < b) -> opposite vertices of the triangles using it
  std::map<std::pair<int, int>, std::vector<std::int32_t>> edges;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const auto& tri = triangles[t];
    for (int k = 0; k < 3; ++k)
      if (tri[k] < 0 || std::size_t(tri[k]) >= n)
        throw InputError(f, "triangles[" + std::to_string(t) + "]", "index out of range");
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k], b = tri[(k + 1) % 3], o = tri[(k + 2) % 3];
      if (a == b) throw InputError(f, "triangles[" + std::to_string(t) + "]", "degenerate triangle");
      edges[{std::min(a, b), std::max(a, b)}].push_back(o);
    }
  }
  PbdConstraintBlock<T> dist, bend;
  dist.kind = PbdConstraintKind::Distance;
  bend.kind = PbdConstraintKind::Bending;
  dist.stiffness = bend.stiffness = T(opt.pbd_stiffness);
  for (const auto& [e, opp] : edges) {
    dist.ids.push_back(e.first);
    dist.ids.push_back(e.second);
    dist.offsets.push_back(std::int32_t(dist.ids.size()));
    dist.rest.push_back(T(norm(vertices[e.first] - vertices[e.second])));
    dist.compliance.push_back(T(opt.stretch_compliance));
    if (opp.size() == 2) {
      const std::int32_t ids[4] = {e.first, e.second, opp[0], opp[1]};
      bend.ids.insert(bend.ids.end(), ids, ids + 4);
      bend.offsets.push_back(std::int32_t(bend.ids.size()));
      bend.rest.push_back(
          T(pbd::dihedralAngle(vertices[ids[0]], vertices[ids[1]], vertices[ids[2]], vertices[ids[3]])));
      bend.compliance.push_back(T(opt.bending_compliance));
    }
  }
  m.blocks.push_back(std::move(dist));
  if (bend.count() > 0) m.blocks.push_back(std::move(bend));
  m.overlap_offsets.assign(n + 1, 0);
  finalizePbdModel(m);
  return m;
}

template PbdModel<float> buildMetaballPbdModel<float>(const MetaballModel&, const MetaballPbdOptions&);
template PbdModel<double> buildMetaballPbdModel<double>(const MetaballModel&, const MetaballPbdOptions&);
template PbdModel<float> buildSheetPbdModel<float>(const std::vector<Vec3d>&,
                                                   const std::vector<std::array<std::int32_t, 3>>&,
                                                   const std::vector<double>&, const SheetPbdOptions&);
template PbdModel<double> buildSheetPbdModel<double>(const std::vector<Vec3d>&,
                                                     const std::vector<std::array<std::int32_t, 3>>&,
                                                     const std::vector<double>&, const SheetPbdOptions&);

}  // namespace inc
