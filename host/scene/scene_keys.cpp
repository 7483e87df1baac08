// The scene format's key table (one row per documented key, with its binding) and the key lists derived from it.
#include "host/scene/scene_keys.h"

#include <sstream>

#include "host/scene/scene_fields.h"

namespace inc {

namespace {

// Messages shared by several keys' rules (scene_fields.h: the text after the range, the unit vector's reasons).
const char* kCoulomb = " (a Coulomb coefficient; 0: frictionless)";
FieldRule unitDirection() { return unitVector("must be a non-zero vector", "is too large to normalise"); }
FieldRule hapticUnit() { return unitVector("must be a non-zero, finite vector", "must be a non-zero, finite vector"); }

bool frictionSet(const ToolSpec& t) { return t.friction != 0.0; }  // a scalpel has none (cutting.blade_friction)
bool anyCollider(const Scene& s) { return !s.colliders.empty(); }

// A member the Scene inherits from CompiledScene, as a member of the Scene: the top-level rows bind the Scene's
// fields, and a member pointer to the base would name the base's type.
template <class C>
constexpr C Scene::*onScene(C CompiledScene::*m) {
  return m;
}
bool surfacePointSet(const HapticsSpec& h) { return h.has_surface_point; }
bool bem(const HapticsSpec& h) { return h.global_model == "bem"; }
bool named(const HapticDeviceSpec& d) { return !d.name.empty(); }
bool trajectorySet(const HapticDeviceSpec& d) { return !d.trajectory.empty(); }

}  // namespace

const std::vector<SceneKey>& sceneKeys() {
  using namespace fields;
  using G = GeometrySpec;
  using Cut = CutThresholds<double>;
  using Dev = HapticDeviceSpec;
  using K = GeometrySpec::Kind;
  static const std::vector<SceneKey> keys = {
      // The file's stem is the name's default: parseScene sets it before the table reads the key.
      {"name", "string", "-", "any", "the file name without extension", text(&Scene::name)},
      {"description", "string", "-", "any", "\"\"", text(&Scene::description)},
      {"duration_s", "number", "s", "> 0", "1.0", number(&Scene::duration, above(0))},
      {"geometry", "object", "-", "-", "required", object(onScene(&Scene::geometry))},
      {"material", "object", "-", "-", "all defaults", object(onScene(&Scene::material))},
      {"models", "object", "-", "-", "all defaults", object(onScene(&Scene::models))},
      {"mls", "object", "-", "-", "all defaults", object(onScene(&Scene::mls))},
      {"pbd", "object", "-", "-", "all defaults", object(onScene(&Scene::pbd))},
      {"solver", "object", "-", "-", "all defaults", object(onScene(&Scene::solver))},
      {"fixed", "array of objects", "-", "-", "[]", array(onScene(&Scene::fixed))},
      {"tools", "array of objects", "-", "-", "[]", array(onScene(&Scene::tools))},
      {"colliders", "array of objects", "-", "at most 8 planes and 8 boxes", "[]",
       array(onScene(&Scene::colliders)).when(anyCollider)},
      {"output", "object", "-", "-", "all defaults", object(&Scene::output)},
      {"tearing", "object", "-", "-", "all defaults", object(onScene(&Scene::tearing))},
      {"cutting", "object", "-", "-", "all defaults", object(onScene(&Scene::cutting))},
      {"haptics", "object", "-", "-", "all defaults", object(onScene(&Scene::haptics))},
      {"geometry.kind", "string", "-", "box, beam, sphere, ellipsoid, mesh", "required",
       choiceOf(
           &G::kind,
           {{"box", K::Box}, {"beam", K::Beam}, {"sphere", K::Sphere}, {"ellipsoid", K::Ellipsoid}, {"mesh", K::Mesh}})
           .required("one of: box, beam, sphere, ellipsoid, mesh")},
      {"geometry.center_m", "vec3", "m", "finite", "[0, 0, 0]", vec3(&G::center), "box beam sphere ellipsoid"},
      {"geometry.size_m", "vec3", "m", "each > 0", "[0.1, 0.02, 0.02]", vec3(&G::size, eachAbove0()), "box beam"},
      {"geometry.radius_m", "number", "m", "> 0", "0.05", number(&G::radius, above(0)), "sphere"},
      {"geometry.radii_m", "vec3", "m", "each > 0", "[0.05, 0.03, 0.02]", vec3(&G::radii, eachAbove0()), "ellipsoid"},
      {"geometry.mesh", "string", "-", "a readable .obj, .ply (ASCII or binary) or .stl (ASCII or binary) file",
       "required for mesh",
       text(&G::mesh_path)
           .readByCode("required for kind mesh, resolved against the scene's folder and loaded to check "
                       "the mesh"),
       "mesh"},
      {"geometry.mesh_scale", "number", "m per file unit", "> 0", "1.0", number(&G::mesh_scale, above(0)), "mesh"},
      {"geometry.spacing_m", "number", "m", "> 0, smaller than the thinnest extent of the body",
       "0.005; mesh: chosen from its volume and area", number(&G::spacing, above(0))},
      {"geometry.jitter", "number", "fraction of spacing_m", "[0, 0.5)", "0.0",
       number(&G::jitter, interval("[0, 0.5)"))},
      {"geometry.seed", "integer", "-", "[0, 4294967295]", "1", integer(&G::seed, interval("[0, 4294967295]"))},
      // Material's ranges are validateMaterial's (material_checks.h), the one check every builder also calls.
      {"material.youngs_modulus_pa", "number", "Pa", "> 0", "3000", number(&Material::youngs_modulus_pa)},
      {"material.poisson_ratio", "number", "-", "(-1, 0.5)", "0.45", number(&Material::poisson_ratio)},
      {"material.density_kg_m3", "number", "kg/m^3", "> 0", "1060", number(&Material::density_kg_m3)},
      {"material.damping_per_s", "number", "1/s", ">= 0", "1.0", number(&Material::damping_per_s)},
      {"material.cutting", "object", "-", "-", "all defaults", sceneObject(onScene(&Scene::cut_thresholds))},
      // The cutting force model's ranges are validateCutThresholds' (cutting_scene.h), which the haptic code shares.
      {"material.cutting.press_threshold_n", "number", "N", ">= 0", "1.0", number(&Cut::press_n)},
      {"material.cutting.static_friction_n", "number", "N", "> 0", "0.6", number(&Cut::static_n)},
      {"material.cutting.dynamic_friction_n", "number", "N", "> 0 and < static_friction_n", "0.3",
       number(&Cut::dynamic_n)},
      {"material.cutting.friction_n_per_m", "number", "N/m", ">= 0", "200", number(&Cut::friction_per_depth_n_per_m)},
      {"models.mls", "boolean", "-", "-", "false", boolean(&ModelsSpec::mls)},
      {"models.pbd_metaballs", "boolean", "-", "-", "false", boolean(&ModelsSpec::pbd_metaballs)},
      {"models.cutting", "boolean", "-", "-", "false", boolean(&ModelsSpec::cutting)},
      {"models.tearing", "boolean", "-", "-", "false", boolean(&ModelsSpec::tearing)},
      {"models.haptics", "boolean", "-", "-", "false", boolean(&ModelsSpec::haptics)},
      {"mls.support_factor", "number", "multiple of spacing_m", "[1.2, 4]", "2.0",
       number(&MlsSpec::support_factor, interval("[1.2, 4]"))},
      {"mls.volume_preservation", "boolean", "-", "-", "true", boolean(&MlsSpec::volume_preservation)},
      {"mls.volume_stiffness", "number", "multiple of the bulk modulus", ">= 0", "1.0",
       number(&MlsSpec::volume_stiffness, atLeast(0))},
      {"mls.condition_limit", "number", "-", "> 1", "1e6",
       number(&MlsSpec::condition_limit, above(1, " (a condition number is >= 1)"))},
      // Bounded so that a frame's work is (model/frame_budget.h), as cutting.pbd_iterations.
      {"pbd.iterations", "integer", "-", "[1, 1000]", "10", integer(&PbdSpec::iterations, interval("[1, 1000]"))},
      {"pbd.xpbd", "boolean", "-", "-", "true", boolean(&PbdSpec::xpbd)},
      {"pbd.solver", "string", "-", "jacobi, gauss_seidel", "jacobi",
       choice(&PbdSpec::solver, {"jacobi", "gauss_seidel"})},
      // Its range depends on pbd.solver: checkChebyshevRho (model/pbd_model.h) in readPbd.
      {"pbd.chebyshev_rho", "number", "-", "[0, 0.9]", "0", number(&PbdSpec::chebyshev_rho)},
      {"pbd.stretch_compliance", "number", "m/N", ">= 0", "0", number(&PbdSpec::stretch_compliance, atLeast(0))},
      {"pbd.laplacian_compliance", "number", "m/N", ">= 0", "0", number(&PbdSpec::laplacian_compliance, atLeast(0))},
      {"pbd.volume_preservation", "boolean", "-", "-", "true", boolean(&PbdSpec::volume_preservation)},
      {"pbd.target_spheres", "integer", "-", ">= 0", "0", integer(&PbdSpec::target_spheres, atLeast(0))},
      {"solver.frame_dt_s", "number", "s", "> 0", "1/60", number(&SolverSpec::frame_dt, above(0))},
      {"solver.substeps", "integer", "-", ">= 0", "0", integer(&SolverSpec::substeps, atLeast(0))},
      {"solver.safety", "number", "-", "(0, 1]", "0.5", number(&SolverSpec::safety, interval("(0, 1]"))},
      // 0: the frame budget's limit for the model's size (model/frame_budget.h); the top is kMlsMaxSubsteps.
      {"solver.max_substeps", "integer", "-", "[0, 10000000]", "0",
       integer(&SolverSpec::max_substeps, interval("[0, 10000000]"))},
      // "float"/"double" are accepted as the C++ names of the same two precisions.
      {"solver.precision", "string", "-", "float32, float64 (also float, double)", "float32",
       choiceOf(&SolverSpec::precision, {{"float32", Precision::Float32},
                                         {"float64", Precision::Float64},
                                         {"float", Precision::Float32},
                                         {"double", Precision::Float64}})},
      {"solver.backend", "string", "-", "auto, cuda, cpu", "auto",
       choiceOf(&SolverSpec::backend,
                {{"auto", BackendKind::Auto}, {"cuda", BackendKind::Cuda}, {"cpu", BackendKind::Cpu}})},
      {"solver.gravity_m_s2", "vec3", "m/s^2", "finite", "[0, 0, -9.81]", vec3(&SolverSpec::gravity)},
      {"solver.energy_bound", "number", "-", "> 1", "1000", number(&SolverSpec::energy_bound, above(1))},
      {"fixed[].min_m", "vec3", "m", "finite", "required", vec3(&FixedRegion::min).required("the box's low corner, m")},
      {"fixed[].max_m", "vec3", "m", ">= min_m in every component (a flat box is allowed)", "required",
       vec3(&FixedRegion::max).required("the box's high corner, m")},
      // tool<index> is set by readTools before the table reads the key, which checks it is non-empty and unique.
      {"tools[].name", "string", "-", "non-empty, unique among tools", "tool<index>", text(&ToolSpec::name)},
      {"tools[].kind", "string", "-", "probe, grasper, scalpel", "probe",
       choice(&ToolSpec::kind, {"probe", "grasper", "scalpel"})},
      {"tools[].radius_m", "number", "m", "> 0", "0.002", number(&ToolSpec::radius, above(0))},
      {"tools[].length_m", "number", "m", "> 0", "0.02", number(&ToolSpec::length, above(0))},
      {"tools[].friction", "number", "-", "[0, 2]", "0",
       number(&ToolSpec::friction, interval("[0, 2]", kCoulomb)).when(frictionSet)},
      {"tools[].path", "array of keyframes", "-", "at least one", "required", array(&ToolSpec::path)},
      {"tools[].path[].t_s", "number", "s", ">= 0, strictly increasing along the path", "required",
       number(&ToolKeyframe::t, atLeast(0)).required("keyframe time, s")},
      {"tools[].path[].position_m", "vec3", "m", "finite", "required",
       vec3(&ToolKeyframe::position).required("tool tip position, m")},
      {"tools[].path[].direction", "vec3", "-", "non-zero; normalised on load", "[0, 0, -1]",
       vec3(&ToolKeyframe::direction, unitDirection())},
      {"colliders[].kind", "string", "-", "plane, box", "required",
       choice(&ColliderSpec::kind, {"plane", "box"}).required("\"plane\" or \"box\"")},
      {"colliders[].point_m", "vec3", "m", "finite", "required (plane)",
       vec3(&ColliderSpec::point).required("a point on the plane, m"), "plane"},
      {"colliders[].normal", "vec3", "-", "non-zero; normalised on load", "required (plane)",
       vec3(&ColliderSpec::normal, unitDirection()).required("the plane's normal, pointing to the free side"), "plane"},
      {"colliders[].min_m", "vec3", "m", "min_m < max_m in every component", "required (box)",
       vec3(&ColliderSpec::min).required("the box's low corner, m"), "box"},
      {"colliders[].max_m", "vec3", "m", "min_m < max_m in every component", "required (box)",
       vec3(&ColliderSpec::max).required("the box's high corner, m"), "box"},
      {"colliders[].friction", "number", "-", "[0, 2]", "0 (frictionless)",
       number(&ColliderSpec::friction, interval("[0, 2]", kCoulomb))},
      {"cutting.samples_per_diameter", "integer", "cells", "[2, 12]", "4",
       integer(&CuttingSpec::samples_per_diameter, interval("[2, 12]"))},
      {"cutting.exchanges_per_frame", "integer", "-", "[1, 64]", "4",
       integer(&CuttingSpec::exchanges_per_frame, interval("[1, 64]"))},
      {"cutting.pbd_substeps_per_exchange", "integer", "-", "[1, 64]", "1",
       integer(&CuttingSpec::pbd_substeps_per_exchange, interval("[1, 64]"))},
      {"cutting.pbd_iterations", "integer", "-", "[0, 1000]", "0",
       integer(&CuttingSpec::pbd_iterations, interval("[0, 1000]"))},
      {"cutting.mls_substeps_per_exchange", "integer", "-", "[0, 100000]", "0",
       integer(&CuttingSpec::mls_substeps_per_exchange, interval("[0, 100000]"))},
      {"cutting.repack_boundary_offset", "number", "fraction of the support radius", "(0, 1)", "0.3",
       number(&CuttingSpec::repack_boundary_offset, interval("(0, 1)", " (a fraction of the support radius)"))},
      {"cutting.repack_spacing_factor", "number", "-", "(0, 4]", "0.5",
       number(&CuttingSpec::repack_spacing_factor, interval("(0, 4]", " (eq. 14 uses 0.5)"))},
      {"cutting.repack_sphere_budget", "number", "spheres per organ sphere's mass", "(0, 8]", "1",
       number(&CuttingSpec::repack_sphere_budget, interval("(0, 8]", " (new spheres per converted sphere's mass)"))},
      {"cutting.stroke_end_frames", "integer", "frames", "[0, 120]", "0",
       integer(&CuttingSpec::stroke_end_frames, interval("[0, 120]"))},
      {"cutting.conversion_delay_frames", "integer", "frames", "[0, 1]", "0",
       integer(&CuttingSpec::conversion_delay_frames, interval("[0, 1]"))},
      {"cutting.open_surface_frames", "integer", "frames", "[0, 120]", "0",
       integer(&CuttingSpec::open_surface_frames, interval("[0, 120]"))},
      {"cutting.blade_radius_m", "number", "m", "[0, 0.05]", "0",
       number(&CuttingSpec::blade_radius_m, interval("[0, 0.05]", " m (the blade's contact capsule; 0: none)"))},
      {"cutting.blade_friction", "number", "-", "[0, 2]", "0",
       number(&CuttingSpec::blade_friction, interval("[0, 2]", kCoulomb))},
      {"tearing.criterion", "string", "-", "traditional, tresca, tresca_principal", "tresca",
       choice(&TearingSpec::criterion, {"traditional", "tresca", "tresca_principal"})},
      {"tearing.k_pa", "number", "Pa", ">= 0", "0", number(&TearingSpec::k_pa, atLeast(0))},
      {"tearing.tau_f_pa", "number", "Pa", ">= 0", "0", number(&TearingSpec::tau_f_pa, atLeast(0))},
      {"tearing.break_strain", "number", "-", "> 0", "0.2", number(&TearingSpec::break_strain, above(0))},
      {"tearing.random_range", "number", "-", "[0, 1)", "0.1",
       number(&TearingSpec::random_range, interval("[0, 1)", " (a fraction of the debris position)"))},
      {"tearing.seed", "integer", "-", "[0, 4294967295]", "1",
       integer(&TearingSpec::seed, interval("[0, 4294967295]"))},
      {"tearing.regions", "array", "-", "-", "[]", array(&TearingSpec::regions)},
      {"tearing.regions[].min_m", "vec3", "m", "finite", "required",
       vec3(&TearingRegionSpec::min).required("the region's low corner, m")},
      {"tearing.regions[].max_m", "vec3", "m", ">= min_m in every component", "required",
       vec3(&TearingRegionSpec::max).required("the region's high corner, m")},
      {"tearing.regions[].k_pa", "number", "Pa", ">= 0", "0", number(&TearingRegionSpec::k_pa, atLeast(0))},
      {"tearing.regions[].tau_f_pa", "number", "Pa", ">= 0", "0", number(&TearingRegionSpec::tau_f_pa, atLeast(0))},
      // The single-device form (devices_listed false) has one device's keys in `haptics` itself.
      {"haptics.devices", "array of objects", "-", "1 to 4 devices", "- (one device: its keys in haptics itself)",
       arrayOrSingle(&HapticsSpec::devices, &HapticsSpec::devices_listed)},
      {"haptics.surface_point_m", "vec3", "m", "finite", "the model's point farthest along surface_normal",
       vec3(&HapticsSpec::surface_point_m).when(surfacePointSet)},
      {"haptics.surface_normal", "vec3", "-", "non-zero; normalised on load", "[0, 0, 1]",
       vec3(&HapticsSpec::surface_normal, hapticUnit())},
      {"haptics.local_radius_m", "number", "m", "> 0", "0.008", number(&HapticsSpec::local_radius_m, above(0))},
      {"haptics.local_spacing_m", "number", "m", "(0, local_radius_m / 2], at most 64 shells", "0.002",
       number(&HapticsSpec::local_spacing_m, above(0))},
      {"haptics.record_trajectory", "boolean", "-", "-", "false", boolean(&HapticsSpec::record_trajectory)},
      {"haptics.global_model", "string", "-", "none, bem", "none", choice(&HapticsSpec::global_model, {"none", "bem"})},
      {"haptics.global_mesh", "string", "-",
       "a readable .obj, .ply or .stl: closed, manifold, consistently oriented, positive volume, no degenerate "
       "triangle, at most 1500 triangles, at least one triangle centroid inside a fixed box",
       "- (required with bem)",
       text(&HapticsSpec::global_mesh)
           .when(bem)
           .readByCode("required with bem, resolved against the scene's folder and loaded to check the organ mesh")},
      {"haptics.global_mesh_scale", "number", "m per file unit", "> 0", "1.0",
       number(&HapticsSpec::global_mesh_scale, above(0)).when(bem)},
      {"haptics.global_cache", "string", "-", "a writable file path",
       "the scene file's name with .bemcache for .json, in its folder (touch.json: touch.bemcache; a scene without a "
       "file: <global_mesh>.bemcache)",
       text(&HapticsSpec::global_cache).when(bem).readByCode("resolved; its default comes from the scene file's name")},
      // hand<i> (the list form) or "" is set by readHapticsSpec before the table reads the key; it checks the name.
      {"haptics.devices[].name", "string", "-", "1-32 letters, digits, _, -; unique among the devices",
       "hand<i> (the list form)", text(&Dev::name).when(named)},
      {"haptics.devices[].device", "string", "-", "scripted, udp, openhaptics", "scripted",
       choice(&Dev::device, {"scripted", "udp", "openhaptics"})},
      {"haptics.devices[].trajectory", "string", "-", "a readable trajectory file",
       "- (required by incision run with scripted)",
       text(&Dev::trajectory)
           .when(trajectorySet)
           .readByCode("resolved against the scene's folder and loaded to check it")},
      {"haptics.devices[].playback", "string", "-", "time, tick", "time", choice(&Dev::playback, {"time", "tick"})},
      {"haptics.devices[].udp_port", "integer", "-", "[1, 65535]; one device per port", "47000",
       integer(&Dev::udp_port, interval("[1, 65535]"))},
      {"haptics.devices[].udp_device", "integer", "-", "[0, 65535]", "0",
       integer(&Dev::udp_device, interval("[0, 65535]"))},
      {"haptics.devices[].openhaptics_device", "string", "-", "any", "\"\"", text(&Dev::openhaptics_device)},
      {"haptics.devices[].workspace_scale", "number", "-", "> 0", "1.0", number(&Dev::workspace_scale, above(0))},
      {"haptics.devices[].workspace_offset_m", "vec3", "m", "finite", "[0, 0, 0]", vec3(&Dev::workspace_offset_m)},
      {"haptics.devices[].max_force_n", "number", "N", "> 0", "3.3", number(&Dev::max_force_n, above(0))},
      {"haptics.devices[].rate_hz", "number", "Hz", "[100, 10000]", "1000",
       number(&Dev::rate_hz, interval("[100, 10000]", " Hz"))},
      {"haptics.devices[].max_force_rate_n_per_s", "number", "N/s", "> 0", "1000",
       number(&Dev::max_force_rate_n_per_s, above(0))},
      {"haptics.devices[].realtime", "boolean", "-", "-", "true", boolean(&Dev::realtime)},
      {"haptics.devices[].cpu", "integer", "-", "[-1, 4095]", "-1", integer(&Dev::cpu, interval("[-1, 4095]"))},
      {"haptics.devices[].tool", "string", "-", "auto, scalpel, probe", "auto",
       choice(&Dev::tool, {"auto", "scalpel", "probe"})},
      {"haptics.devices[].blade_length_m", "number", "m", "> 0", "0.05", number(&Dev::blade_length_m, above(0))},
      {"haptics.devices[].blade_axis", "vec3", "-", "non-zero; normalised on load", "[0, 0, 1]",
       vec3(&Dev::blade_axis, hapticUnit())},
      {"output.every_frames", "integer", "frames", ">= 0", "0", integer(&OutputSpec::every_frames, atLeast(0))},
      {"output.particles_ply", "boolean", "-", "-", "true", boolean(&OutputSpec::particles_ply)},
      {"output.mesh_obj", "boolean", "-", "-", "true", boolean(&OutputSpec::mesh_obj)},
      {"output.vtk", "boolean", "-", "-", "false", boolean(&OutputSpec::vtk)},
      {"output.metrics_csv", "boolean", "-", "-", "true", boolean(&OutputSpec::metrics_csv)},
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

std::vector<SceneRow> sceneRowsUnder(const std::string& parent) {
  std::vector<SceneRow> out;
  for (const SceneKey& k : sceneKeys()) {
    std::string name = childName(k.path, parent);
    if (!name.empty()) out.push_back({&k, std::move(name)});
  }
  return out;
}

bool sceneKeyUsedBy(const SceneKey& key, const std::string& kind) {
  return key.kinds[0] == '\0' || namesKind(key.kinds, kind);
}

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
