// A scene's haptic loops: one hand per device, the tissue plane, the MFS tip contact, the scalpel, the frame hooks.
#include "host/haptics/scene_haptics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "base/format_number.h"
#include "host/compiled/bem_organ_mesh.h"
#include "host/haptics/udp_device.h"
#include "model/input_error.h"
#if INCISION_HAVE_OPENHAPTICS
#include "host/haptics/openhaptics_device.h"
#endif

namespace inc {

TissuePlane sceneTissuePlane(const CompiledScene& scene, const SimulationModel& model) {
  TissuePlane p;
  p.normal = scene.haptics.surface_normal;
  if (scene.haptics.has_surface_point) {
    p.point_m = scene.haptics.surface_point_m;
    return p;
  }
  TriangleMesh surface;
  std::vector<Vec3d> points;
  if (model.currentSurface(surface) && !surface.vertices.empty())
    points = surface.vertices;
  else
    model.currentPositions(points);
  if (points.empty())
    throw InputError(scene.file, "haptics.surface_point_m",
                     "the model has no points to find its surface from; give the tissue plane");
  double best = -std::numeric_limits<double>::infinity();
  for (const Vec3d& x : points)
    if (dot(x, p.normal) > best) {
      best = dot(x, p.normal);
      p.point_m = x;
    }
  return p;
}

std::unique_ptr<HapticDevice> makeSceneHapticDevice(const CompiledScene& scene, std::size_t index) {
  const HapticsSpec& hs = scene.haptics;
  if (index >= hs.devices.size()) throw InputError(scene.file, "haptics.devices", "no device " + std::to_string(index));
  const HapticDeviceSpec& h = hs.devices[index];
  const auto key = [&](const char* k) { return hapticDeviceKey(hs, index, k); };
  if (h.device == "scripted") {
    if (h.trajectory.empty())
      throw InputError(scene.file, key("trajectory"),
                       "is required for device \"scripted\" (a trajectory file: t x y z qw qx qy qz buttons per line; "
                       "`incision view` drives the first device's tip with the mouse instead)");
    Trajectory tr;
    try {
      tr = loadTrajectory(h.trajectory);
    } catch (const InputError& e) {
      throw InputError(scene.file, key("trajectory"), e.what());
    }
    const auto mode = h.playback == "tick" ? ScriptedDevice::Mode::kByTick : ScriptedDevice::Mode::kByTime;
    return std::make_unique<ScriptedDevice>(std::move(tr), mode, h.max_force_n);
  }
  if (h.device == "udp") {
    try {
      return std::make_unique<UdpDevice>(std::uint16_t(h.udp_port), std::uint16_t(h.udp_device), h.max_force_n);
    } catch (const InputError& e) {
      throw InputError(scene.file, key("udp_port"), e.what());
    }
  }
  if (h.device == "openhaptics") {
#if INCISION_HAVE_OPENHAPTICS
    OpenHapticsMapping map;
    map.scale = h.workspace_scale;
    map.offset_m = h.workspace_offset_m;
    try {
      return std::make_unique<OpenHapticsDevice>(h.openhaptics_device, map);
    } catch (const InputError& e) {
      throw InputError(scene.file, key("device"), e.what());
    }
#else
    throw InputError(scene.file, key("device"), "the OpenHaptics driver is not built (no SDK found by CMake)");
#endif
  }
  throw InputError(scene.file, key("device"), "unknown device \"" + h.device + "\"");
}

namespace {

HapticLoopConfig loopConfig(const CompiledScene& scene, const HapticDeviceSpec& h, double record_s) {
  HapticLoopConfig c;
  c.rate_hz = h.rate_hz;
  c.max_force_rate_n_per_s = h.max_force_rate_n_per_s;
  c.realtime = h.realtime;
  c.cpu = h.cpu;
  // The simulation thread late by more than a frame: its data is two frames old.
  c.stall_after_s = std::max(2.0 * scene.solver.frame_dt, 1.0 / 30.0);
  c.record_capacity = std::size_t(std::ceil(std::clamp(record_s, 1.0, 3600.0) * h.rate_hz));
  return c;
}

// Which device holds the scalpel on `model`: the one whose tool is "scalpel", else the first "auto" one on a
// model that can be cut; -1: none. Throws for a scalpel on a model that cannot be cut.
long scalpelHand(const CompiledScene& scene, const SimulationModel& model) {
  const auto& devices = scene.haptics.devices;
  const bool can_cut = model.toolSupport().cut;
  for (std::size_t k = 0; k < devices.size(); ++k)
    if (devices[k].tool == "scalpel") {
      if (!can_cut)
        throw InputError(scene.file, hapticDeviceKey(scene.haptics, k, "tool"),
                         "\"scalpel\": the model the tools touch (" + model.name() + ") cannot be cut");
      return long(k);
    }
  if (!can_cut) return -1;
  for (std::size_t k = 0; k < devices.size(); ++k)
    if (devices[k].tool == "auto") return long(k);
  return -1;
}

// The scene's BEM organ (global_model "bem"): mesh, supports, the local model's cloud; errors name
// haptics.global_mesh. The tissue plane's point must lie near the organ: a wrong global_mesh_scale or a mesh of
// another organ would otherwise couple every contact to a far-away element.
std::unique_ptr<GlobalOrganModel> sceneGlobalModel(const CompiledScene& scene, const TissuePlane& plane, int hands,
                                                   bool quiet) {
  const HapticsSpec& h = scene.haptics;
  const std::string key = "haptics.global_mesh";
  GlobalOrganSetup setup;
  try {
    setup.mesh = loadGlobalOrganMesh(h.global_mesh, h.global_mesh_scale);
  } catch (const InputError& e) {
    throw InputError(scene.file, key, e.what());
  }
  const MeshReport rep = analyzeMesh(setup.mesh);
  Vec3d gap;
  for (int a = 0; a < 3; ++a)
    gap[a] = std::max({rep.bbox_min[a] - plane.point_m[a], plane.point_m[a] - rep.bbox_max[a], 0.0});
  const double diag = norm(rep.bbox_max - rep.bbox_min);
  if (norm(gap) > 0.1 * diag)
    throw InputError(scene.file, key,
                     h.global_mesh + ": the organ mesh lies " + formatNumber(norm(gap)) +
                         " m from the tissue plane's point (its box is " + formatNumber(diag) +
                         " m across): is global_mesh_scale right, and is it the mesh of this organ?");
  setup.supports = organSupports(setup.mesh, scene.fixed);
  setup.material = scene.material;
  setup.local.inner_spacing_m = h.local_spacing_m;
  setup.local.inner_shells = 2;  // as mfsTipStiffness: the held and the coupled local model are the same cloud
  setup.local.radius_m = h.local_radius_m;
  setup.cache_path = h.global_cache;
  setup.quiet = quiet;
  try {
    return std::make_unique<GlobalOrganModel>(std::move(setup), hands);
  } catch (const InputError& e) {
    throw InputError(scene.file, key, e.what());
  }
}

}  // namespace

SceneHaptics::SceneHaptics(const CompiledScene& scene, const SimulationModel& model, SceneHapticsOptions options) {
  const HapticsSpec& h = scene.haptics;
  if (h.devices.empty()) throw InputError(scene.file, "haptics.devices", "lists no device");
  if (options.clock && h.devices.size() > 1)
    throw InputError(scene.file, "haptics.devices", "one test clock cannot drive several loop threads");
  plane_ = sceneTissuePlane(scene, model);
  tip_ = mfsTipStiffness(scene.material, h.local_radius_m, h.local_spacing_m, plane_.normal);
  const long scalpel = scalpelHand(scene, model);
  if (h.global_model == "bem") organ_ = sceneGlobalModel(scene, plane_, int(h.devices.size()), options.quiet);
  // Every device is built before any loop exists: a device that cannot be opened starts nothing.
  std::vector<std::shared_ptr<HapticDevice>> devices;
  for (std::size_t k = 0; k < h.devices.size(); ++k)
    devices.push_back(k == 0 && options.device ? options.device
                                               : std::shared_ptr<HapticDevice>(makeSceneHapticDevice(scene, k)));
  for (std::size_t k = 0; k < h.devices.size(); ++k) {
    const HapticDeviceSpec& d = h.devices[k];
    HapticHandConfig c;
    c.name = d.name;
    c.counter_prefix = k == 0 ? "haptic" : "haptic" + std::to_string(k);
    c.scalpel = long(k) == scalpel;
    c.plane = plane_;
    c.elastic = organ_ ? organ_->contactElastic(int(k)) : tipElastic(tip_);
    c.cut = scene.cut_thresholds;
    c.blade_length_m = d.blade_length_m;
    c.blade_axis_device = d.blade_axis;
    c.frame_dt_s = scene.solver.frame_dt;
    c.max_cut_lag_s = options.max_cut_lag_s;
    c.loop = loopConfig(scene, d, options.record_s);
    hands_.push_back(std::make_unique<HapticHand>(devices[k], c, options.clock));
  }
}

SceneHaptics::~SceneHaptics() { stop(); }

void SceneHaptics::start() {
  for (auto& hnd : hands_) hnd->start();
}

void SceneHaptics::stop() {
  for (auto& hnd : hands_) hnd->stop();
}

void SceneHaptics::beforeFrame(SimulationModel& model) {
  for (auto& hnd : hands_) hnd->beforeFrame(model);
}

void SceneHaptics::afterFrame(FrameReport& report) {
  for (auto& hnd : hands_) hnd->afterFrame(report);
  if (organ_) {  // the global model at the visual rate: once per frame
    organ_->step();
    report.counters["haptic_organ_max_displacement_m"] = organ_->maxSurfaceDisplacement_m();
    report.counters["haptic_organ_contacts"] = organ_->contacts();
  }
}

bool SceneHaptics::cutting() const {
  for (const auto& hnd : hands_)
    if (hnd->scalpel()) return true;
  return false;
}

int SceneHaptics::cutDecisions() const {
  int n = 0;
  for (const auto& hnd : hands_) n += hnd->cutDecisions();
  return n;
}

int SceneHaptics::cutsApplied() const {
  int n = 0;
  for (const auto& hnd : hands_) n += hnd->cutsApplied();
  return n;
}

std::string SceneHaptics::summary() const {
  std::string out;
  for (const auto& hnd : hands_) out += (out.empty() ? "" : "; ") + hnd->summary();
  if (organ_) out += "; " + organ_->summary();
  return out;
}

std::vector<std::string> SceneHaptics::writeRecordings(const std::string& dir) const {
  std::vector<std::string> files;
  for (const auto& hnd : hands_) {
    const std::string suffix = hnd->name().empty() ? "" : "_" + hnd->name();
    const std::string traj = (std::filesystem::path(dir) / ("haptic_trajectory" + suffix + ".traj")).string();
    const std::string forces = (std::filesystem::path(dir) / ("haptic_forces" + suffix + ".txt")).string();
    writeTrajectory(traj, hnd->loop().recordedTrajectory());
    writeTickForces(forces, hnd->loop().records());
    files.push_back(traj);
    files.push_back(forces);
  }
  return files;
}

}  // namespace inc
