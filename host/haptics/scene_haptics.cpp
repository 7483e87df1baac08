// A scene's haptic loop: its device, the tissue plane, the MFS tip contact or cutting tool, and the frame hooks.
#include "host/haptics/scene_haptics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "host/haptics/haptics_scene.h"
#include "host/haptics/udp_device.h"
#include "host/input_error.h"
#if INCISION_HAVE_OPENHAPTICS
#include "host/haptics/openhaptics_device.h"
#endif

namespace inc {

TissuePlane sceneTissuePlane(const Scene& scene, const SimulationModel& model) {
  TissuePlane p;
  p.normal = scene.haptics.surface_normal;
  if (scene.haptics.has_surface_point) {
    p.point_m = scene.haptics.surface_point_m;
    return p;
  }
  TriangleMesh surface;
  std::vector<Vec3d> points;
  if (model.currentSurface(surface) && !surface.vertices.empty()) points = surface.vertices;
  else model.currentPositions(points);
  if (points.empty()) throw InputError(scene.file, "haptics.surface_point_m", "the model has no points to find its surface from; give the tissue plane");
  double best = -std::numeric_limits<double>::infinity();
  for (const Vec3d& x : points)
    if (dot(x, p.normal) > best) {
      best = dot(x, p.normal);
      p.point_m = x;
    }
  return p;
}

std::unique_ptr<HapticDevice> makeSceneHapticDevice(const Scene& scene) {
  const HapticsSpec& h = scene.haptics;
  if (h.device == "scripted") {
    if (h.trajectory.empty())
      throw InputError(scene.file, "haptics.trajectory",
                       "is required for device \"scripted\" (a trajectory file: t x y z qw qx qy qz buttons per line; "
                       "`incision view` drives the tip with the mouse instead)");
    Trajectory tr;
    try {
      tr = loadTrajectory(h.trajectory);
    } catch (const InputError& e) {
      throw InputError(scene.file, "haptics.trajectory", e.what());
    }
    const auto mode = h.playback == "tick" ? ScriptedDevice::Mode::kByTick : ScriptedDevice::Mode::kByTime;
    return std::make_unique<ScriptedDevice>(std::move(tr), mode, h.max_force_n);
  }
  if (h.device == "udp") {
    try {
      return std::make_unique<UdpDevice>(std::uint16_t(h.udp_port), std::uint16_t(h.udp_device), h.max_force_n);
    } catch (const InputError& e) {
      throw InputError(scene.file, "haptics.udp_port", e.what());
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
      throw InputError(scene.file, "haptics.device", e.what());
    }
#else
    throw InputError(scene.file, "haptics.device", "the OpenHaptics driver is not built (no SDK found by CMake)");
#endif
  }
  throw InputError(scene.file, "haptics.device", "unknown device \"" + h.device + "\"");
}

namespace {

HapticLoopConfig loopConfig(const Scene& scene, double record_s) {
  const HapticsSpec& h = scene.haptics;
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

}  // namespace

SceneHaptics::SceneHaptics(const Scene& scene, const SimulationModel& model, SceneHapticsOptions options)
    : device_(options.device) {
  if (!device_) device_ = makeSceneHapticDevice(scene);
  plane_ = sceneTissuePlane(scene, model);
  const HapticsSpec& h = scene.haptics;
  tip_ = mfsTipStiffness(MfsMaterial{scene.material.youngs_modulus, scene.material.poisson_ratio}, h.local_radius_m,
                         h.local_spacing_m, plane_.normal);
  const CuttingTool::Elastic elastic = tipElastic(tip_);
  const HapticLoopConfig config = loopConfig(scene, options.record_s);
  if (model.toolSupport().cut) {
    cut_tool_ = std::make_unique<CuttingTool>(elastic, scene.material.cutting, plane_.point_m, plane_.normal);
    RealtimeCutConfig rc;
    rc.blade_length_m = h.blade_length_m;
    rc.blade_axis_device = h.blade_axis;
    rc.loop = config;
    cut_session_ = std::make_unique<RealtimeHapticCutSession>(*device_, *cut_tool_, rc, options.clock);
  } else {
    probe_ = std::make_unique<ProbeTool>(elastic, plane_.point_m, plane_.normal);
    probe_loop_ = std::make_unique<HapticLoop>(
        *device_, [this](const ForceRequest& q) { return probe_link_.stamp(probe_->tick(q), q.t_s); }, config,
        options.clock);
  }
}

SceneHaptics::~SceneHaptics() { stop(); }

const HapticLoop& SceneHaptics::loop() const { return cut_session_ ? cut_session_->loop() : *probe_loop_; }

void SceneHaptics::start() {
  if (cut_session_) {
    cut_session_->start();
  } else {
    probe_link_.setDataTime(0.0);  // a first frame that never ends fades the force like any later stall
    probe_loop_->start();
  }
}

void SceneHaptics::stop() {
  if (cut_session_) cut_session_->stop();
  else if (probe_loop_) probe_loop_->stop();
}

void SceneHaptics::beforeFrame(SimulationModel& model) {
  if (cut_session_) cut_session_->applyDecisions(model);
}

void SceneHaptics::afterFrame(FrameReport& report) {
  const HapticWindow w = cut_session_ ? cut_session_->frameDone() : probe_link_.frameDone();
  report.counters["haptic_hz"] = w.rate_hz;
  report.counters["haptic_p99_ms"] = w.p99_ms;
  if (cut_session_) {
    report.counters["haptic_cut_decisions"] = cut_session_->decisions();
    newest_ = cut_session_->newestStatus();
  } else {
    probe_loop_->status().update();
    newest_ = probe_loop_->status().front();
  }
}

std::string SceneHaptics::summary() const {
  const PeriodStats s = stats();
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "haptic loop %.0f Hz, device %s, %s: %llu ticks, period p50 %.3f ms, p99 %.3f ms, max %.3f ms, "
                "missed %llu, skipped %llu, compute p99 %.1f us",
                1.0 / loop().period_s(), device_->name().c_str(), scheduling().realtime ? "SCHED_FIFO" : "normal scheduling",
                static_cast<unsigned long long>(s.ticks), 1e3 * s.p50_s, 1e3 * s.p99_s, 1e3 * s.max_s,
                static_cast<unsigned long long>(s.missed), static_cast<unsigned long long>(s.skipped),
                1e6 * s.compute_p99_s);
  std::string out = buf;
  if (cut_session_)
    out += ", cut decisions " + std::to_string(cut_session_->decisions()) + ", cuts applied " +
           std::to_string(cut_session_->cutsApplied());
  return out;
}

}  // namespace inc
