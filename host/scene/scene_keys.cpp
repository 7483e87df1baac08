// The scene format's key table (one entry per documented key) and the key lists the loader derives from it.
#include "host/scene/scene_keys.h"

#include <sstream>

namespace inc {

const std::vector<SceneKey>& sceneKeys() {
  static const std::vector<SceneKey> keys = {
    {"name", "string", "-", "any", "the file name without extension"},
    {"description", "string", "-", "any", "\"\""},
    {"duration_s", "number", "s", "> 0", "1.0"},
    {"geometry", "object", "-", "-", "required"},
    {"material", "object", "-", "-", "all defaults"},
    {"models", "object", "-", "-", "all defaults"},
    {"mls", "object", "-", "-", "all defaults"},
    {"pbd", "object", "-", "-", "all defaults"},
    {"solver", "object", "-", "-", "all defaults"},
    {"fixed", "array of objects", "-", "-", "[]"},
    {"tools", "array of objects", "-", "-", "[]"},
    {"colliders", "array of objects", "-", "at most 8 planes and 8 boxes", "[]"},
    {"output", "object", "-", "-", "all defaults"},
    {"tearing", "object", "-", "-", "all defaults"},
    {"cutting", "object", "-", "-", "all defaults"},
    {"haptics", "object", "-", "-", "all defaults"},
    {"geometry.kind", "string", "-", "box, beam, sphere, ellipsoid, mesh", "required"},
    {"geometry.center_m", "vec3", "m", "finite", "[0, 0, 0]", "box beam sphere ellipsoid"},
    {"geometry.size_m", "vec3", "m", "each > 0", "[0.1, 0.02, 0.02]", "box beam"},
    {"geometry.radius_m", "number", "m", "> 0", "0.05", "sphere"},
    {"geometry.radii_m", "vec3", "m", "each > 0", "[0.05, 0.03, 0.02]", "ellipsoid"},
    {"geometry.mesh", "string", "-",
     "a readable .obj, .ply (ASCII or binary) or .stl (ASCII or binary) file",
     "required for mesh", "mesh"},
    {"geometry.mesh_scale", "number", "m per file unit", "> 0", "1.0", "mesh"},
    {"geometry.spacing_m", "number", "m", "> 0, smaller than the thinnest extent of the body", "0.005"},
    {"geometry.jitter", "number", "fraction of spacing_m", "[0, 0.5)", "0.0"},
    {"geometry.seed", "integer", "-", "[0, 4294967295]", "1"},
    {"material.youngs_modulus_pa", "number", "Pa", "> 0", "3000"},
    {"material.poisson_ratio", "number", "-", "(-1, 0.5)", "0.45"},
    {"material.density_kg_m3", "number", "kg/m^3", "> 0", "1060"},
    {"material.damping_per_s", "number", "1/s", ">= 0", "1.0"},
    {"material.cutting", "object", "-", "-", "all defaults"},
    {"material.cutting.press_threshold_n", "number", "N", ">= 0", "1.0"},
    {"material.cutting.static_friction_n", "number", "N", "> 0", "0.6"},
    {"material.cutting.dynamic_friction_n", "number", "N", "> 0 and < static_friction_n", "0.3"},
    {"material.cutting.friction_n_per_m", "number", "N/m", ">= 0", "200"},
    {"models.mls", "boolean", "-", "-", "false"},
    {"models.pbd_metaballs", "boolean", "-", "-", "false"},
    {"models.cutting", "boolean", "-", "-", "false"},
    {"models.tearing", "boolean", "-", "-", "false"},
    {"models.haptics", "boolean", "-", "-", "false"},
    {"mls.support_factor", "number", "multiple of spacing_m", "[1.2, 4]", "2.0"},
    {"mls.volume_preservation", "boolean", "-", "-", "true"},
    {"mls.volume_stiffness", "number", "multiple of the bulk modulus", ">= 0", "1.0"},
    {"mls.condition_limit", "number", "-", "> 1", "1e6"},
    {"pbd.iterations", "integer", "-", ">= 1", "10"},
    {"pbd.xpbd", "boolean", "-", "-", "true"},
    {"pbd.solver", "string", "-", "jacobi, gauss_seidel", "jacobi"},
    {"pbd.chebyshev_rho", "number", "-", "[0, 0.9]", "0"},
    {"pbd.stretch_compliance", "number", "m/N", ">= 0", "0"},
    {"pbd.laplacian_compliance", "number", "m/N", ">= 0", "0"},
    {"pbd.volume_preservation", "boolean", "-", "-", "true"},
    {"pbd.target_spheres", "integer", "-", ">= 0", "0"},
    {"solver.frame_dt_s", "number", "s", "> 0", "1/60"},
    {"solver.substeps", "integer", "-", ">= 0", "0"},
    {"solver.safety", "number", "-", "(0, 1]", "0.5"},
    {"solver.precision", "string", "-", "float32, float64 (also float, double)", "float32"},
    {"solver.backend", "string", "-", "auto, cuda, cpu", "auto"},
    {"solver.gravity_m_s2", "vec3", "m/s^2", "finite", "[0, 0, -9.81]"},
    {"solver.energy_bound", "number", "-", "> 1", "1000"},
    {"fixed[].min_m", "vec3", "m", "finite", "required"},
    {"fixed[].max_m", "vec3", "m", ">= min_m in every component (a flat box is allowed)", "required"},
    {"tools[].name", "string", "-", "non-empty, unique among tools", "tool<index>"},
    {"tools[].kind", "string", "-", "probe, grasper, scalpel", "probe"},
    {"tools[].radius_m", "number", "m", "> 0", "0.002"},
    {"tools[].length_m", "number", "m", "> 0", "0.02"},
    {"tools[].friction", "number", "-", "[0, 2]", "0"},
    {"tools[].path", "array of keyframes", "-", "at least one", "required"},
    {"tools[].path[].t_s", "number", "s", ">= 0, strictly increasing along the path", "required"},
    {"tools[].path[].position_m", "vec3", "m", "finite", "required"},
    {"tools[].path[].direction", "vec3", "-", "non-zero; normalised on load", "[0, 0, -1]"},
    {"colliders[].kind", "string", "-", "plane, box", "required"},
    {"colliders[].point_m", "vec3", "m", "finite", "required (plane)", "plane"},
    {"colliders[].normal", "vec3", "-", "non-zero; normalised on load", "required (plane)", "plane"},
    {"colliders[].min_m", "vec3", "m", "min_m < max_m in every component", "required (box)", "box"},
    {"colliders[].max_m", "vec3", "m", "min_m < max_m in every component", "required (box)", "box"},
    {"colliders[].friction", "number", "-", "[0, 2]", "0 (frictionless)"},
    {"cutting.samples_per_diameter", "integer", "cells", "[2, 12]", "4"},
    {"cutting.exchanges_per_frame", "integer", "-", "[1, 64]", "4"},
    {"cutting.pbd_substeps_per_exchange", "integer", "-", "[1, 64]", "1"},
    {"cutting.pbd_iterations", "integer", "-", "[0, 1000]", "0"},
    {"cutting.mls_substeps_per_exchange", "integer", "-", "[0, 100000]", "0"},
    {"cutting.repack_boundary_offset", "number", "fraction of the support radius", "(0, 1)", "0.3"},
    {"cutting.repack_spacing_factor", "number", "-", "(0, 4]", "0.5"},
    {"cutting.repack_sphere_budget", "number", "spheres per organ sphere's mass", "(0, 8]", "1"},
    {"cutting.stroke_end_frames", "integer", "frames", "[0, 120]", "0"},
    {"cutting.conversion_delay_frames", "integer", "frames", "[0, 1]", "0"},
    {"cutting.open_surface_frames", "integer", "frames", "[0, 120]", "0"},
    {"cutting.blade_radius_m", "number", "m", "[0, 0.05]", "0"},
    {"cutting.blade_friction", "number", "-", "[0, 2]", "0"},
    {"tearing.criterion", "string", "-", "traditional, tresca, tresca_principal", "tresca"},
    {"tearing.k_pa", "number", "Pa", ">= 0", "0"},
    {"tearing.tau_f_pa", "number", "Pa", ">= 0", "0"},
    {"tearing.break_strain", "number", "-", "> 0", "0.2"},
    {"tearing.random_range", "number", "-", "[0, 1)", "0.1"},
    {"tearing.seed", "integer", "-", "[0, 4294967295]", "1"},
    {"tearing.regions", "array", "-", "-", "[]"},
    {"tearing.regions[].min_m", "vec3", "m", "finite", "required"},
    {"tearing.regions[].max_m", "vec3", "m", ">= min_m in every component", "required"},
    {"tearing.regions[].k_pa", "number", "Pa", ">= 0", "0"},
    {"tearing.regions[].tau_f_pa", "number", "Pa", ">= 0", "0"},
    {"haptics.devices", "array of objects", "-", "1 to 4 devices", "- (one device: its keys in haptics itself)"},
    {"haptics.surface_point_m", "vec3", "m", "finite", "the model's point farthest along surface_normal"},
    {"haptics.surface_normal", "vec3", "-", "non-zero; normalised on load", "[0, 0, 1]"},
    {"haptics.local_radius_m", "number", "m", "> 0", "0.008"},
    {"haptics.local_spacing_m", "number", "m", "(0, local_radius_m / 2], at most 64 shells", "0.002"},
    {"haptics.record_trajectory", "boolean", "-", "-", "false"},
    {"haptics.global_model", "string", "-", "none, bem", "none"},
    {"haptics.global_mesh", "string", "-",
     "a readable .obj, .ply or .stl: closed, manifold, consistently oriented, positive volume, no degenerate "
     "triangle, at most 1500 triangles, at least one triangle centroid inside a fixed box",
     "- (required with bem)"},
    {"haptics.global_mesh_scale", "number", "m per file unit", "> 0", "1.0"},
    {"haptics.global_cache", "string", "-", "a writable file path",
     "the scene file's name with .bemcache for .json, in its folder (touch.json: touch.bemcache; a scene without a "
     "file: <global_mesh>.bemcache)"},
    {"haptics.devices[].name", "string", "-",
     "1-32 letters, digits, _, -; unique among the devices",
     "hand<i> (the list form)"},
    {"haptics.devices[].device", "string", "-", "scripted, udp, openhaptics", "scripted"},
    {"haptics.devices[].trajectory", "string", "-",
     "a readable trajectory file",
     "- (required by incision run with scripted)"},
    {"haptics.devices[].playback", "string", "-", "time, tick", "time"},
    {"haptics.devices[].udp_port", "integer", "-", "[1, 65535]; one device per port", "47000"},
    {"haptics.devices[].udp_device", "integer", "-", "[0, 65535]", "0"},
    {"haptics.devices[].openhaptics_device", "string", "-", "any", "\"\""},
    {"haptics.devices[].workspace_scale", "number", "-", "> 0", "1.0"},
    {"haptics.devices[].workspace_offset_m", "vec3", "m", "finite", "[0, 0, 0]"},
    {"haptics.devices[].max_force_n", "number", "N", "> 0", "3.3"},
    {"haptics.devices[].rate_hz", "number", "Hz", "[100, 10000]", "1000"},
    {"haptics.devices[].max_force_rate_n_per_s", "number", "N/s", "> 0", "1000"},
    {"haptics.devices[].realtime", "boolean", "-", "-", "true"},
    {"haptics.devices[].cpu", "integer", "-", "[-1, 4095]", "-1"},
    {"haptics.devices[].tool", "string", "-", "auto, scalpel, probe", "auto"},
    {"haptics.devices[].blade_length_m", "number", "m", "> 0", "0.05"},
    {"haptics.devices[].blade_axis", "vec3", "-", "non-zero; normalised on load", "[0, 0, 1]"},
    {"output.every_frames", "integer", "frames", ">= 0", "0"},
    {"output.particles_ply", "boolean", "-", "-", "true"},
    {"output.mesh_obj", "boolean", "-", "-", "true"},
    {"output.vtk", "boolean", "-", "-", "false"},
    {"output.metrics_csv", "boolean", "-", "-", "true"},
  };
  return keys;
}

namespace {

// "material.cutting" under "material" -> "cutting"; "" when `path` is not a direct child of `parent`.
std::string childName(const std::string& path, const std::string& parent) {
  std::string rest = path;
  if (!parent.empty()) {
    if (path.size() <= parent.size() + 1 || path.compare(0, parent.size(), parent) != 0 || path[parent.size()] != '.')
      return "";
    rest = path.substr(parent.size() + 1);
  }
  return rest.find_first_of(".[") == std::string::npos ? rest : "";
}

bool namesKind(const char* kinds, const std::string& kind) {
  std::istringstream words(kinds);
  for (std::string w; words >> w;)
    if (w == kind) return true;
  return false;
}

}  // namespace

std::vector<std::string> sceneKeysUnder(const std::string& parent, const std::string& kind) {
  std::vector<std::string> out;
  for (const SceneKey& k : sceneKeys()) {
    const std::string name = childName(k.path, parent);
    if (name.empty()) continue;
    if (!kind.empty() && k.kinds[0] != '\0' && !namesKind(k.kinds, kind)) continue;
    out.push_back(name);
  }
  return out;
}

std::vector<std::string> kindSpecificKeysUnder(const std::string& parent) {
  std::vector<std::string> out;
  for (const SceneKey& k : sceneKeys()) {
    const std::string name = childName(k.path, parent);
    if (!name.empty() && k.kinds[0] != '\0') out.push_back(name);
  }
  return out;
}

std::vector<std::string> kindSpecificKeysUnder(const std::string& parent, const std::string& kind) {
  std::vector<std::string> out;
  for (const SceneKey& k : sceneKeys()) {
    const std::string name = childName(k.path, parent);
    if (!name.empty() && namesKind(k.kinds, kind)) out.push_back(name);
  }
  return out;
}

}  // namespace inc
