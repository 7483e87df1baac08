// Scene schema: reads each JSON section into the Scene struct with types, units and ranges checked (docs/scene-format.md).
#include "host/scene/scene_loader.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <system_error>

#include "host/scene/cutting_scene.h"
#include "host/scene/haptics_scene.h"
#include "host/compiled/material_checks.h"
#include "host/scene/scene_keys.h"
#include "model/input_error.h"
#include "host/io/mesh.h"
#include "model/pbd_model.h"
#include "host/scene/scene_json.h"

namespace inc {

namespace {

using scene_json::formatNumber;
using scene_json::ObjectReader;

// Guard against a slip in spacing_m (5e-5 for 5e-3) that would ask for more particles than any machine holds.
constexpr double kMaxEstimatedParticles = 5.0e7;

std::string got(double v) { return " (got " + formatNumber(v) + ")"; }

double positive(const ObjectReader& r, const std::string& key, double fallback) {
  const double v = r.number(key, fallback);
  if (!(v > 0)) r.fail(key, "must be > 0" + got(v));
  return v;
}

double nonNegative(const ObjectReader& r, const std::string& key, double fallback) {
  const double v = r.number(key, fallback);
  if (!(v >= 0)) r.fail(key, "must be >= 0" + got(v));
  return v;
}

int intAtLeast(const ObjectReader& r, const std::string& key, int fallback, int min) {
  const long long v = r.integer(key, fallback);
  if (v < min) r.fail(key, "must be >= " + std::to_string(min) + " (got " + std::to_string(v) + ")");
  if (v > std::numeric_limits<int>::max()) r.fail(key, "is too large (got " + std::to_string(v) + ")");
  return static_cast<int>(v);
}

Vec3d positiveVec3(const ObjectReader& r, const std::string& key, const Vec3d& fallback) {
  const Vec3d v = r.vec3(key, fallback);
  for (int c = 0; c < 3; ++c) {
    if (!(v[c] > 0)) r.fail(key, "every component must be > 0 (component " + std::to_string(c) + " is " +
                                     formatNumber(v[c]) + ")");
  }
  return v;
}

const char* kindName(GeometrySpec::Kind k) {
  switch (k) {
    case GeometrySpec::Kind::Box: return "box";
    case GeometrySpec::Kind::Beam: return "beam";
    case GeometrySpec::Kind::Sphere: return "sphere";
    case GeometrySpec::Kind::Ellipsoid: return "ellipsoid";
    case GeometrySpec::Kind::Mesh: return "mesh";
  }
  return "?";
}

// Loads and checks the mesh of a "mesh" geometry; returns its extent and volume in metres for the sampling checks.
void checkMeshGeometry(const ObjectReader& g, const GeometrySpec& spec, double& min_extent, double& volume) {
  TriangleMesh mesh;
  try {
    mesh = loadMesh(spec.mesh_path);
    requireClosedMesh(mesh, spec.mesh_path, "");
  } catch (const InputError& e) {
    g.fail("mesh", e.what());
  }
  const MeshReport rep = analyzeMesh(mesh);
  const Vec3d ext = (rep.bbox_max - rep.bbox_min) * spec.mesh_scale;
  min_extent = std::min({ext.x, ext.y, ext.z});
  volume = rep.signed_volume * spec.mesh_scale * spec.mesh_scale * spec.mesh_scale;
}

GeometrySpec readGeometry(const ObjectReader& top, const std::string& base_dir) {
  const ObjectReader g = top.object("geometry");
  g.allowOnly(sceneKeysUnder("geometry"));
  if (!g.has("kind")) g.fail("kind", "is required (one of: box, beam, sphere, ellipsoid, mesh)");
  const std::string kind = g.choice("kind", "", {"box", "beam", "sphere", "ellipsoid", "mesh"});
  GeometrySpec s;
  if (kind == "box") s.kind = GeometrySpec::Kind::Box;
  if (kind == "beam") s.kind = GeometrySpec::Kind::Beam;
  if (kind == "sphere") s.kind = GeometrySpec::Kind::Sphere;
  if (kind == "ellipsoid") s.kind = GeometrySpec::Kind::Ellipsoid;
  if (kind == "mesh") s.kind = GeometrySpec::Kind::Mesh;

  // A key that belongs to another kind is a mistake the user should hear about, not a silent no-op.
  const std::vector<std::string> own = kindSpecificKeysUnder("geometry", kind);
  for (const std::string& k : kindSpecificKeysUnder("geometry")) {
    if (g.has(k) && std::find(own.begin(), own.end(), k) == own.end()) {
      g.fail(k, std::string("is not used by geometry.kind \"") + kind + "\"");
    }
  }

  s.center = g.vec3("center_m", s.center);
  s.size = positiveVec3(g, "size_m", s.size);
  s.radius = positive(g, "radius_m", s.radius);
  s.radii = positiveVec3(g, "radii_m", s.radii);
  s.mesh_scale = positive(g, "mesh_scale", s.mesh_scale);
  s.spacing = positive(g, "spacing_m", s.spacing);
  s.jitter = g.number("jitter", s.jitter);
  if (!(s.jitter >= 0 && s.jitter < 0.5)) g.fail("jitter", "must lie in [0, 0.5)" + got(s.jitter));
  const long long seed = g.integer("seed", s.seed);
  if (seed < 0 || seed > static_cast<long long>(std::numeric_limits<unsigned>::max()))
    g.fail("seed", "must lie in [0, 4294967295] (got " + std::to_string(seed) + ")");
  s.seed = static_cast<unsigned>(seed);

  double min_extent = 0, volume = 0;
  const double pi = 3.14159265358979323846;
  switch (s.kind) {
    case GeometrySpec::Kind::Box:
    case GeometrySpec::Kind::Beam:
      min_extent = std::min({s.size.x, s.size.y, s.size.z});
      volume = s.size.x * s.size.y * s.size.z;
      break;
    case GeometrySpec::Kind::Sphere:
      min_extent = 2 * s.radius;
      volume = 4.0 / 3.0 * pi * s.radius * s.radius * s.radius;
      break;
    case GeometrySpec::Kind::Ellipsoid:
      min_extent = 2 * std::min({s.radii.x, s.radii.y, s.radii.z});
      volume = 4.0 / 3.0 * pi * s.radii.x * s.radii.y * s.radii.z;
      break;
    case GeometrySpec::Kind::Mesh: {
      if (!g.has("mesh")) g.fail("mesh", "is required when geometry.kind is \"mesh\" (a .obj, .ply or .stl file)");
      const std::string rel = g.string("mesh", "");
      if (rel.empty()) g.fail("mesh", "must name a mesh file");
      s.mesh_path = scene_json::resolvePath(rel, base_dir);
      checkMeshGeometry(g, s, min_extent, volume);
      break;
    }
  }
  if (!(s.spacing < min_extent)) {
    g.fail("spacing_m", formatNumber(s.spacing) + " m is not smaller than the thinnest extent of the geometry (" +
                            formatNumber(min_extent) + " m): the particle lattice would be (almost) empty");
  }
  const double estimate = volume / (s.spacing * s.spacing * s.spacing);
  if (estimate > kMaxEstimatedParticles) {
    g.fail("spacing_m", "would sample about " + formatNumber(std::round(estimate)) + " particles, more than the limit of " +
                            formatNumber(kMaxEstimatedParticles) + "; use a larger spacing");
  }
  return s;
}

// material.*: the numbers read with their types checked, then the ranges by the one Material validation.
void readMaterial(const ObjectReader& top, Material& m, CutThresholds<double>& cutting) {
  if (!top.has("material")) return;
  const ObjectReader r = top.object("material");
  r.allowOnly(sceneKeysUnder("material"));
  m.youngs_modulus_pa = r.number("youngs_modulus_pa", m.youngs_modulus_pa);
  m.poisson_ratio = r.number("poisson_ratio", m.poisson_ratio);
  m.density_kg_m3 = r.number("density_kg_m3", m.density_kg_m3);
  m.damping_per_s = r.number("damping_per_s", m.damping_per_s);
  validateMaterial(m, r.file(), r.path());  // host/compiled/material_checks.h
  if (r.has("cutting")) cutting = readCutThresholds(r.object("cutting"));  // host/scene/cutting_scene.h
}

ModelsSpec readModels(const ObjectReader& top) {
  ModelsSpec m;
  if (top.has("models")) {
    const ObjectReader r = top.object("models");
    r.allowOnly(sceneKeysUnder("models"));
    m.mls = r.boolean("mls", m.mls);
    m.pbd_metaballs = r.boolean("pbd_metaballs", m.pbd_metaballs);
    m.cutting = r.boolean("cutting", m.cutting);
    m.tearing = r.boolean("tearing", m.tearing);
    m.haptics = r.boolean("haptics", m.haptics);
    if (m.cutting && !m.pbd_metaballs)
      r.fail("cutting", "needs models.pbd_metaballs: cutting works on the metaball organ");
  }
  if (!m.mls && !m.pbd_metaballs && !m.tearing) {
    throw InputError(top.file(), "models",
                     "switches on no deformable model: set at least one of models.mls, models.pbd_metaballs or "
                     "models.tearing to true");
  }
  return m;
}

MlsSpec readMls(const ObjectReader& top) {
  MlsSpec m;
  if (!top.has("mls")) return m;
  const ObjectReader r = top.object("mls");
  r.allowOnly(sceneKeysUnder("mls"));
  m.support_factor = r.number("support_factor", m.support_factor);
  if (!(m.support_factor >= 1.2 && m.support_factor <= 4.0))
    r.fail("support_factor", "must lie in [1.2, 4]" + got(m.support_factor));
  m.volume_preservation = r.boolean("volume_preservation", m.volume_preservation);
  m.volume_stiffness = nonNegative(r, "volume_stiffness", m.volume_stiffness);
  m.condition_limit = r.number("condition_limit", m.condition_limit);
  if (!(m.condition_limit > 1)) r.fail("condition_limit", "must be > 1 (a condition number is >= 1)" + got(m.condition_limit));
  return m;
}

PbdSpec readPbd(const ObjectReader& top) {
  PbdSpec p;
  if (!top.has("pbd")) return p;
  const ObjectReader r = top.object("pbd");
  r.allowOnly(sceneKeysUnder("pbd"));
  p.iterations = intAtLeast(r, "iterations", p.iterations, 1);
  p.xpbd = r.boolean("xpbd", p.xpbd);
  p.solver = r.choice("solver", p.solver, {"jacobi", "gauss_seidel"});
  p.chebyshev_rho = r.number("chebyshev_rho", p.chebyshev_rho);
  try {  // the solver's own rule (model/pbd_model.h), reported at this key
    checkChebyshevRho(p.chebyshev_rho, parsePbdSolver(p.solver, "", ""), "", "");
  } catch (const InputError& e) {
    r.fail("chebyshev_rho", e.reason());
  }
  p.stretch_compliance = nonNegative(r, "stretch_compliance", p.stretch_compliance);
  p.laplacian_compliance = nonNegative(r, "laplacian_compliance", p.laplacian_compliance);
  p.volume_preservation = r.boolean("volume_preservation", p.volume_preservation);
  p.target_spheres = intAtLeast(r, "target_spheres", p.target_spheres, 0);
  return p;
}

SolverSpec readSolver(const ObjectReader& top) {
  SolverSpec s;
  if (!top.has("solver")) return s;
  const ObjectReader r = top.object("solver");
  r.allowOnly(sceneKeysUnder("solver"));
  s.frame_dt = positive(r, "frame_dt_s", s.frame_dt);
  s.substeps = intAtLeast(r, "substeps", s.substeps, 0);
  s.safety = r.number("safety", s.safety);
  if (!(s.safety > 0 && s.safety <= 1)) r.fail("safety", "must lie in (0, 1]" + got(s.safety));
  // "float"/"double" are accepted as the C++ names of the same two precisions.
  const std::string prec =
      r.choice("precision", precisionName(s.precision), {"float32", "float64", "float", "double"});
  s.precision = (prec == "float64" || prec == "double") ? Precision::Float64 : Precision::Float32;
  const std::string backend = r.choice("backend", backendName(s.backend), {"auto", "cuda", "cpu"});
  s.backend = parseBackend(backend, r.file(), r.keyPath("backend"));
  s.gravity = r.vec3("gravity_m_s2", s.gravity);
  s.energy_bound = r.number("energy_bound", s.energy_bound);
  if (!(s.energy_bound > 1)) r.fail("energy_bound", "must be > 1" + got(s.energy_bound));
  return s;
}

std::vector<FixedRegion> readFixed(const ObjectReader& top) {
  std::vector<FixedRegion> out;
  const nlohmann::json* arr = top.array("fixed");
  if (!arr) return out;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const ObjectReader r((*arr)[i], top.file(), scene_json::indexPath(top.keyPath("fixed"), i));
    r.allowOnly(sceneKeysUnder("fixed[]"));
    if (!r.has("min_m")) r.fail("min_m", "is required (the box's low corner, m)");
    if (!r.has("max_m")) r.fail("max_m", "is required (the box's high corner, m)");
    FixedRegion f;
    f.min = r.vec3("min_m", f.min);
    f.max = r.vec3("max_m", f.max);
    for (int c = 0; c < 3; ++c) {
      if (!(f.min[c] <= f.max[c])) {
        r.fail("max_m", "must be >= min_m in every component (component " + std::to_string(c) + ": " +
                            formatNumber(f.max[c]) + " < " + formatNumber(f.min[c]) + ")");
      }
    }
    out.push_back(f);
  }
  return out;
}

Vec3d unitDirection(const ObjectReader& r, const std::string& key, const Vec3d& fallback) {
  Vec3d d = r.vec3(key, fallback);
  const double n2 = norm2(d);
  if (!(n2 > 0)) r.fail(key, "must be a non-zero vector");
  if (!std::isfinite(n2)) r.fail(key, "is too large to normalise");
  // Leave a vector that is unit to rounding as it is, so that writing and re-reading a scene changes nothing.
  if (std::fabs(n2 - 1.0) > 8 * std::numeric_limits<double>::epsilon()) d = d * (1.0 / std::sqrt(n2));
  return d;
}

// colliders: planes {"kind": "plane", "point_m", "normal"} and boxes {"kind": "box", "min_m", "max_m"}.
std::vector<ColliderSpec> readColliders(const ObjectReader& top, const ModelsSpec& models) {
  std::vector<ColliderSpec> out;
  const nlohmann::json* arr = top.array("colliders");
  if (!arr) return out;
  int planes = 0, boxes = 0;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const ObjectReader r((*arr)[i], top.file(), scene_json::indexPath(top.keyPath("colliders"), i));
    ColliderSpec c;
    if (!r.has("kind")) r.fail("kind", "is required (\"plane\" or \"box\")");
    c.kind = r.choice("kind", c.kind, {"plane", "box"});
    if (c.kind == "plane") {
      r.allowOnly(sceneKeysUnder("colliders[]", "plane"));
      if (!r.has("point_m")) r.fail("point_m", "is required (a point on the plane, m)");
      if (!r.has("normal")) r.fail("normal", "is required (the plane's normal, pointing to the free side)");
      c.point = r.vec3("point_m", c.point);
      c.normal = unitDirection(r, "normal", c.normal);
      if (++planes > kMaxCollidersPerKind)
        r.fail("kind", "more than " + std::to_string(kMaxCollidersPerKind) + " planes in one scene");
    } else {
      r.allowOnly(sceneKeysUnder("colliders[]", "box"));
      if (!r.has("min_m")) r.fail("min_m", "is required (the box's low corner, m)");
      if (!r.has("max_m")) r.fail("max_m", "is required (the box's high corner, m)");
      c.min = r.vec3("min_m", c.min);
      c.max = r.vec3("max_m", c.max);
      for (int k = 0; k < 3; ++k)
        if (!(c.min[k] < c.max[k]))
          r.fail("max_m", "must be > min_m in every component (component " + std::to_string(k) + ": " +
                              formatNumber(c.max[k]) + " <= " + formatNumber(c.min[k]) + ")");
      if (++boxes > kMaxCollidersPerKind)
        r.fail("kind", "more than " + std::to_string(kMaxCollidersPerKind) + " boxes in one scene");
    }
    c.friction = r.number("friction", c.friction);
    if (!(c.friction >= 0 && c.friction <= 2))
      r.fail("friction", "must lie in [0, 2] (a Coulomb coefficient; 0: frictionless)" + got(c.friction));
    out.push_back(c);
  }
  // The tearing sheet has no contacts: a collider there would be passed through.
  if (!out.empty() && models.tearing)
    top.fail("colliders", "act on the PBD metaball organ, the MLS body and a cut's nodal points; models.tearing's "
                          "sheet would pass through them");
  return out;
}

std::vector<ToolSpec> readTools(const ObjectReader& top) {
  std::vector<ToolSpec> out;
  const nlohmann::json* arr = top.array("tools");
  if (!arr) return out;
  std::set<std::string> names;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const ObjectReader r((*arr)[i], top.file(), scene_json::indexPath(top.keyPath("tools"), i));
    r.allowOnly(sceneKeysUnder("tools[]"));
    ToolSpec t;
    t.name = r.string("name", "tool" + std::to_string(i));
    if (t.name.empty()) r.fail("name", "must not be empty");
    if (!names.insert(t.name).second) r.fail("name", "\"" + t.name + "\" names two tools; tool names must be unique");
    t.kind = r.choice("kind", t.kind, {"probe", "grasper", "scalpel"});
    t.radius = positive(r, "radius_m", t.radius);
    t.length = positive(r, "length_m", t.length);
    if (r.has("friction") && t.kind == "scalpel")
      r.fail("friction", "a scalpel's contact friction is cutting.blade_friction (with cutting.blade_radius_m)");
    t.friction = r.number("friction", t.friction);
    if (!(t.friction >= 0 && t.friction <= 2))
      r.fail("friction", "must lie in [0, 2] (a Coulomb coefficient; 0: frictionless)" + got(t.friction));
    const nlohmann::json* path = r.array("path");
    if (!path || path->empty()) r.fail("path", "needs at least one keyframe {\"t_s\", \"position_m\"}");
    for (std::size_t k = 0; k < path->size(); ++k) {
      const ObjectReader kr((*path)[k], r.file(), scene_json::indexPath(r.keyPath("path"), k));
      kr.allowOnly(sceneKeysUnder("tools[].path[]"));
      if (!kr.has("t_s")) kr.fail("t_s", "is required (keyframe time, s)");
      if (!kr.has("position_m")) kr.fail("position_m", "is required (tool tip position, m)");
      ToolKeyframe f;
      f.t = kr.number("t_s", 0.0);
      if (!(f.t >= 0)) kr.fail("t_s", "must be >= 0" + got(f.t));
      if (!t.path.empty() && !(f.t > t.path.back().t)) {
        kr.fail("t_s", "keyframe times must increase strictly (" + formatNumber(f.t) + " follows " +
                           formatNumber(t.path.back().t) + ")");
      }
      f.position = kr.vec3("position_m", f.position);
      f.direction = unitDirection(kr, "direction", f.direction);
      t.path.push_back(f);
    }
    out.push_back(t);
  }
  return out;
}

OutputSpec readOutput(const ObjectReader& top) {
  OutputSpec o;
  if (!top.has("output")) return o;
  const ObjectReader r = top.object("output");
  r.allowOnly(sceneKeysUnder("output"));
  o.every_frames = intAtLeast(r, "every_frames", o.every_frames, 0);
  o.particles_ply = r.boolean("particles_ply", o.particles_ply);
  o.mesh_obj = r.boolean("mesh_obj", o.mesh_obj);
  o.vtk = r.boolean("vtk", o.vtk);
  o.metrics_csv = r.boolean("metrics_csv", o.metrics_csv);
  return o;
}

TearingSpec readTearing(const ObjectReader& top) {
  TearingSpec t;
  if (!top.has("tearing")) return t;
  const ObjectReader r = top.object("tearing");
  r.allowOnly(sceneKeysUnder("tearing"));
  t.criterion = r.choice("criterion", t.criterion, {"traditional", "tresca", "tresca_principal"});
  t.k_pa = nonNegative(r, "k_pa", t.k_pa);
  t.tau_f_pa = nonNegative(r, "tau_f_pa", t.tau_f_pa);
  t.break_strain = positive(r, "break_strain", t.break_strain);
  t.random_range = r.number("random_range", t.random_range);
  if (!(t.random_range >= 0 && t.random_range < 1))
    r.fail("random_range", "must lie in [0, 1) (a fraction of the debris position)" + got(t.random_range));
  const long long seed = r.integer("seed", t.seed);
  if (seed < 0 || seed > static_cast<long long>(std::numeric_limits<unsigned>::max()))
    r.fail("seed", "must lie in [0, 4294967295] (got " + std::to_string(seed) + ")");
  t.seed = static_cast<unsigned>(seed);
  const nlohmann::json* arr = r.array("regions");
  if (!arr) return t;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const ObjectReader rr((*arr)[i], r.file(), scene_json::indexPath(r.keyPath("regions"), i));
    rr.allowOnly(sceneKeysUnder("tearing.regions[]"));
    if (!rr.has("min_m")) rr.fail("min_m", "is required (the region's low corner, m)");
    if (!rr.has("max_m")) rr.fail("max_m", "is required (the region's high corner, m)");
    if (!rr.has("k_pa") && !rr.has("tau_f_pa")) rr.fail("k_pa", "a region needs k_pa or tau_f_pa (or both)");
    TearingRegionSpec g;
    g.min = rr.vec3("min_m", g.min);
    g.max = rr.vec3("max_m", g.max);
    for (int c = 0; c < 3; ++c) {
      if (!(g.min[c] <= g.max[c])) {
        rr.fail("max_m", "must be >= min_m in every component (component " + std::to_string(c) + ": " +
                             formatNumber(g.max[c]) + " < " + formatNumber(g.min[c]) + ")");
      }
    }
    g.k_pa = nonNegative(rr, "k_pa", g.k_pa);
    g.tau_f_pa = nonNegative(rr, "tau_f_pa", g.tau_f_pa);
    t.regions.push_back(g);
  }
  return t;
}

int intInRange(const ObjectReader& r, const std::string& key, int fallback, int lo, int hi) {
  const long long v = r.integer(key, fallback);
  if (v < lo || v > hi)
    r.fail(key, "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " + std::to_string(v) + ")");
  return static_cast<int>(v);
}

CuttingSpec readCutting(const ObjectReader& top) {
  CuttingSpec c;
  if (!top.has("cutting")) return c;
  const ObjectReader r = top.object("cutting");
  r.allowOnly(sceneKeysUnder("cutting"));
  c.samples_per_diameter = intInRange(r, "samples_per_diameter", c.samples_per_diameter, 2, 12);
  c.exchanges_per_frame = intInRange(r, "exchanges_per_frame", c.exchanges_per_frame, 1, 64);
  c.pbd_substeps_per_exchange = intInRange(r, "pbd_substeps_per_exchange", c.pbd_substeps_per_exchange, 1, 64);
  c.pbd_iterations = intInRange(r, "pbd_iterations", c.pbd_iterations, 0, 1000);
  c.mls_substeps_per_exchange = intInRange(r, "mls_substeps_per_exchange", c.mls_substeps_per_exchange, 0, 100000);
  c.repack_boundary_offset = r.number("repack_boundary_offset", c.repack_boundary_offset);
  if (!(c.repack_boundary_offset > 0 && c.repack_boundary_offset < 1))
    r.fail("repack_boundary_offset", "must lie in (0, 1) (a fraction of the support radius)" + got(c.repack_boundary_offset));
  c.repack_spacing_factor = r.number("repack_spacing_factor", c.repack_spacing_factor);
  if (!(c.repack_spacing_factor > 0 && c.repack_spacing_factor <= 4))
    r.fail("repack_spacing_factor", "must lie in (0, 4] (eq. 14 uses 0.5)" + got(c.repack_spacing_factor));
  c.repack_sphere_budget = r.number("repack_sphere_budget", c.repack_sphere_budget);
  if (!(c.repack_sphere_budget > 0 && c.repack_sphere_budget <= 8))
    r.fail("repack_sphere_budget", "must lie in (0, 8] (new spheres per converted sphere's mass)" + got(c.repack_sphere_budget));
  c.stroke_end_frames = intInRange(r, "stroke_end_frames", c.stroke_end_frames, 0, 120);
  c.conversion_delay_frames = intInRange(r, "conversion_delay_frames", c.conversion_delay_frames, 0, 1);
  c.open_surface_frames = intInRange(r, "open_surface_frames", c.open_surface_frames, 0, 120);
  c.blade_radius_m = r.number("blade_radius_m", c.blade_radius_m);
  if (!(c.blade_radius_m >= 0 && c.blade_radius_m <= 0.05))
    r.fail("blade_radius_m", "must lie in [0, 0.05] m (the blade's contact capsule; 0: none)" + got(c.blade_radius_m));
  c.blade_friction = r.number("blade_friction", c.blade_friction);
  if (!(c.blade_friction >= 0 && c.blade_friction <= 2))
    r.fail("blade_friction", "must lie in [0, 2] (a Coulomb coefficient; 0: frictionless)" + got(c.blade_friction));
  return c;
}

// nlohmann's indented dump puts each element of an array on its own line; a vec3 reads better as
// [x, y, z]. Joins every array whose elements are all scalars. Safe on strings: a dumped string never
// holds a raw newline, and the scan only acts on '[' that ends a line.
std::string compactScalarArrays(const std::string& text) {
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    const std::size_t open = text.find("[\n", i);
    if (open == std::string::npos) break;
    out.append(text, i, open + 1 - i);
    std::size_t pos = open + 2;
    std::vector<std::string> items;
    bool scalar = true;
    std::size_t close = std::string::npos;
    while (pos < text.size()) {
      const std::size_t eol = text.find('\n', pos);
      std::string line = text.substr(pos, eol == std::string::npos ? std::string::npos : eol - pos);
      const std::size_t first = line.find_first_not_of(' ');
      line = first == std::string::npos ? "" : line.substr(first);
      if (line == "]" || line == "]," ) {
        close = pos + first;
        break;
      }
      if (line.find_first_of("[]{}") != std::string::npos && line.front() != '"') scalar = false;
      if (!line.empty() && line.back() == ',') line.pop_back();
      items.push_back(line);
      if (eol == std::string::npos) break;
      pos = eol + 1;
    }
    if (!scalar || close == std::string::npos) {
      i = open + 1;
      continue;
    }
    for (std::size_t k = 0; k < items.size(); ++k) out += (k ? ", " : "") + items[k];
    i = close;  // continues with the ']' itself
  }
  out.append(text, i, std::string::npos);
  return out;
}

}  // namespace

Scene parseScene(const std::string& json_text, const std::string& file_label, const std::string& base_dir) {
  const nlohmann::json doc = scene_json::parseChecked(json_text, file_label);
  const ObjectReader top(doc, file_label, "");
  top.allowOnly(sceneKeysUnder(""));
  Scene s;
  s.file = file_label;
  s.name = top.string("name", std::filesystem::path(file_label).stem().string());
  s.description = top.string("description", "");
  s.duration = positive(top, "duration_s", s.duration);
  // Sections in the order a reader of the file expects the first error to be reported.
  s.geometry = readGeometry(top, base_dir);
  readMaterial(top, s.material, s.cut_thresholds);
  s.models = readModels(top);
  s.mls = readMls(top);
  s.pbd = readPbd(top);
  s.solver = readSolver(top);
  s.fixed = readFixed(top);
  s.tools = readTools(top);
  s.colliders = readColliders(top, s.models);
  s.output = readOutput(top);
  s.tearing = readTearing(top);
  s.cutting = readCutting(top);
  s.haptics = readHapticsSpec(top, base_dir, s.models, s.fixed);  // host/scene/haptics_scene.h
  return s;
}

Scene loadSceneFile(const std::string& path) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st)) throw InputError(path, "", "cannot open scene file: no such file");
  if (std::filesystem::is_directory(st)) throw InputError(path, "", "cannot read scene file: it is a directory");
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno;
    throw InputError(path, "", std::string("cannot open scene file: ") + (err ? std::strerror(err) : "open failed"));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "cannot read scene file: read error");
  return parseScene(text.str(), path, std::filesystem::path(path).parent_path().string());
}

std::string sceneToJson(const Scene& s) {
  using J = nlohmann::ordered_json;
  auto vec = [](const Vec3d& v) { return J::array({v.x, v.y, v.z}); };
  J j;
  j["name"] = s.name;
  j["description"] = s.description;
  j["duration_s"] = s.duration;

  J g;
  g["kind"] = kindName(s.geometry.kind);
  switch (s.geometry.kind) {
    case GeometrySpec::Kind::Box:
    case GeometrySpec::Kind::Beam:
      g["center_m"] = vec(s.geometry.center);
      g["size_m"] = vec(s.geometry.size);
      break;
    case GeometrySpec::Kind::Sphere:
      g["center_m"] = vec(s.geometry.center);
      g["radius_m"] = s.geometry.radius;
      break;
    case GeometrySpec::Kind::Ellipsoid:
      g["center_m"] = vec(s.geometry.center);
      g["radii_m"] = vec(s.geometry.radii);
      break;
    case GeometrySpec::Kind::Mesh:
      g["mesh"] = s.geometry.mesh_path;
      g["mesh_scale"] = s.geometry.mesh_scale;
      break;
  }
  g["spacing_m"] = s.geometry.spacing;
  g["jitter"] = s.geometry.jitter;
  g["seed"] = s.geometry.seed;
  j["geometry"] = g;

  j["material"] = J{{"youngs_modulus_pa", s.material.youngs_modulus_pa},
                    {"poisson_ratio", s.material.poisson_ratio},
                    {"density_kg_m3", s.material.density_kg_m3},
                    {"damping_per_s", s.material.damping_per_s},
                    {"cutting", cutThresholdsJson(s.cut_thresholds)}};
  j["models"] = J{{"mls", s.models.mls},
                  {"pbd_metaballs", s.models.pbd_metaballs},
                  {"cutting", s.models.cutting},
                  {"tearing", s.models.tearing},
                  {"haptics", s.models.haptics}};
  j["mls"] = J{{"support_factor", s.mls.support_factor},
               {"volume_preservation", s.mls.volume_preservation},
               {"volume_stiffness", s.mls.volume_stiffness},
               {"condition_limit", s.mls.condition_limit}};
  j["pbd"] = J{{"iterations", s.pbd.iterations},
               {"xpbd", s.pbd.xpbd},
               {"solver", s.pbd.solver},
               {"chebyshev_rho", s.pbd.chebyshev_rho},
               {"stretch_compliance", s.pbd.stretch_compliance},
               {"laplacian_compliance", s.pbd.laplacian_compliance},
               {"volume_preservation", s.pbd.volume_preservation},
               {"target_spheres", s.pbd.target_spheres}};
  j["solver"] = J{{"frame_dt_s", s.solver.frame_dt},
                  {"substeps", s.solver.substeps},
                  {"safety", s.solver.safety},
                  {"precision", precisionName(s.solver.precision)},
                  {"backend", backendName(s.solver.backend)},
                  {"gravity_m_s2", vec(s.solver.gravity)},
                  {"energy_bound", s.solver.energy_bound}};
  J fixed = J::array();
  for (const FixedRegion& f : s.fixed) fixed.push_back(J{{"min_m", vec(f.min)}, {"max_m", vec(f.max)}});
  j["fixed"] = fixed;
  J tools = J::array();
  for (const ToolSpec& t : s.tools) {
    J path = J::array();
    for (const ToolKeyframe& k : t.path)
      path.push_back(J{{"t_s", k.t}, {"position_m", vec(k.position)}, {"direction", vec(k.direction)}});
    J tool{{"name", t.name}, {"kind", t.kind}, {"radius_m", t.radius}, {"length_m", t.length}, {"path", path}};
    if (t.friction != 0.0) tool["friction"] = t.friction;  // a scalpel has none (cutting.blade_friction)
    tools.push_back(tool);
  }
  j["tools"] = tools;
  if (!s.colliders.empty()) {
    J colliders = J::array();
    for (const ColliderSpec& c : s.colliders)
      colliders.push_back(c.kind == "plane" ? J{{"kind", "plane"}, {"point_m", vec(c.point)}, {"normal", vec(c.normal)},
                                                {"friction", c.friction}}
                                            : J{{"kind", "box"}, {"min_m", vec(c.min)}, {"max_m", vec(c.max)},
                                                {"friction", c.friction}});
    j["colliders"] = colliders;
  }
  j["output"] = J{{"every_frames", s.output.every_frames},
                  {"particles_ply", s.output.particles_ply},
                  {"mesh_obj", s.output.mesh_obj},
                  {"vtk", s.output.vtk},
                  {"metrics_csv", s.output.metrics_csv}};
  J regions = J::array();
  for (const TearingRegionSpec& g : s.tearing.regions)
    regions.push_back(J{{"min_m", vec(g.min)}, {"max_m", vec(g.max)}, {"k_pa", g.k_pa}, {"tau_f_pa", g.tau_f_pa}});
  j["tearing"] = J{{"criterion", s.tearing.criterion},
                   {"k_pa", s.tearing.k_pa},
                   {"tau_f_pa", s.tearing.tau_f_pa},
                   {"break_strain", s.tearing.break_strain},
                   {"random_range", s.tearing.random_range},
                   {"seed", s.tearing.seed},
                   {"regions", regions}};
  j["cutting"] = J{{"samples_per_diameter", s.cutting.samples_per_diameter},
                   {"exchanges_per_frame", s.cutting.exchanges_per_frame},
                   {"pbd_substeps_per_exchange", s.cutting.pbd_substeps_per_exchange},
                   {"pbd_iterations", s.cutting.pbd_iterations},
                   {"mls_substeps_per_exchange", s.cutting.mls_substeps_per_exchange},
                   {"repack_boundary_offset", s.cutting.repack_boundary_offset},
                   {"repack_spacing_factor", s.cutting.repack_spacing_factor},
                   {"repack_sphere_budget", s.cutting.repack_sphere_budget},
                   {"stroke_end_frames", s.cutting.stroke_end_frames},
                   {"conversion_delay_frames", s.cutting.conversion_delay_frames},
                   {"open_surface_frames", s.cutting.open_surface_frames},
                   {"blade_radius_m", s.cutting.blade_radius_m},
                   {"blade_friction", s.cutting.blade_friction}};
  j["haptics"] = hapticsSpecJson(s.haptics);
  return compactScalarArrays(j.dump(2)) + "\n";
}

}  // namespace inc
