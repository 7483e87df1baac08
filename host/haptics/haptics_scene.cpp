// Scene keys of the haptic loop: haptics.{device, trajectory, playback, udp_*, rate_hz, surface_*, local_*, blade_*}.
#include "host/haptics/haptics_scene.h"

#include <cmath>
#include <filesystem>
#include <limits>

#include "host/haptics/haptic_device.h"
#include "host/input_error.h"

namespace inc {

namespace {

using scene_json::formatNumber;
using scene_json::ObjectReader;

std::string got(double v) { return " (got " + formatNumber(v) + ")"; }

double positiveKey(const ObjectReader& r, const std::string& key, double fallback) {
  const double v = r.number(key, fallback);
  if (!(v > 0)) r.fail(key, "must be > 0" + got(v));
  return v;
}

int intIn(const ObjectReader& r, const std::string& key, int fallback, long long lo, long long hi) {
  const long long v = r.integer(key, fallback);
  if (v < lo || v > hi)
    r.fail(key, "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got " + std::to_string(v) + ")");
  return static_cast<int>(v);
}

Vec3d unitKey(const ObjectReader& r, const std::string& key, const Vec3d& fallback) {
  Vec3d d = r.vec3(key, fallback);
  const double n2 = norm2(d);
  if (!(n2 > 0) || !std::isfinite(n2)) r.fail(key, "must be a non-zero, finite vector");
  // A vector that is unit to rounding stays as it is, so writing and re-reading a scene changes nothing.
  if (std::fabs(n2 - 1.0) > 8 * std::numeric_limits<double>::epsilon()) d = d * (1.0 / std::sqrt(n2));
  return d;
}

std::string resolved(const std::string& path, const std::string& base_dir) {
  std::filesystem::path p(path);
  if (p.is_relative()) p = std::filesystem::path(base_dir.empty() ? "." : base_dir) / p;
  std::error_code ec;
  const std::filesystem::path abs = std::filesystem::absolute(p, ec);
  return (ec ? p : abs).lexically_normal().string();
}

}  // namespace

bool openHapticsBuilt() {
#if INCISION_HAVE_OPENHAPTICS
  return true;
#else
  return false;
#endif
}

HapticsSpec readHapticsSpec(const ObjectReader& top, const std::string& base_dir) {
  HapticsSpec h;
  if (!top.has("haptics")) return h;
  const ObjectReader r = top.object("haptics");
  r.allowOnly({"device", "trajectory", "playback", "udp_port", "udp_device", "openhaptics_device", "workspace_scale",
               "workspace_offset_m", "max_force_n", "rate_hz", "max_force_rate_n_per_s", "realtime", "cpu",
               "surface_point_m", "surface_normal", "local_radius_m", "local_spacing_m", "blade_length_m", "blade_axis",
               "record_trajectory"});
  h.device = r.choice("device", h.device, {"scripted", "udp", "openhaptics"});
  if (h.device == "openhaptics" && !openHapticsBuilt())
    r.fail("device", "the OpenHaptics driver is not built (CMake did not find the SDK: HD/hd.h and libHD; see "
                     "docs/haptics.md); use \"udp\" with an external driver");
  if (r.has("trajectory")) {
    const std::string rel = r.string("trajectory", "");
    if (rel.empty()) r.fail("trajectory", "must name a trajectory file");
    h.trajectory = resolved(rel, base_dir);
    try {
      (void)loadTrajectory(h.trajectory);  // checked once here: the run reads it again
    } catch (const InputError& e) {
      r.fail("trajectory", e.what());
    }
  }
  h.playback = r.choice("playback", h.playback, {"time", "tick"});
  h.udp_port = intIn(r, "udp_port", h.udp_port, 1, 65535);
  h.udp_device = intIn(r, "udp_device", h.udp_device, 0, 65535);
  h.openhaptics_device = r.string("openhaptics_device", h.openhaptics_device);
  h.workspace_scale = positiveKey(r, "workspace_scale", h.workspace_scale);
  h.workspace_offset_m = r.vec3("workspace_offset_m", h.workspace_offset_m);
  h.max_force_n = positiveKey(r, "max_force_n", h.max_force_n);
  h.rate_hz = r.number("rate_hz", h.rate_hz);
  if (!(h.rate_hz >= 100.0 && h.rate_hz <= 10000.0)) r.fail("rate_hz", "must lie in [100, 10000] Hz" + got(h.rate_hz));
  h.max_force_rate_n_per_s = positiveKey(r, "max_force_rate_n_per_s", h.max_force_rate_n_per_s);
  h.realtime = r.boolean("realtime", h.realtime);
  h.cpu = intIn(r, "cpu", h.cpu, -1, 4095);
  h.has_surface_point = r.has("surface_point_m");
  h.surface_point_m = r.vec3("surface_point_m", h.surface_point_m);
  h.surface_normal = unitKey(r, "surface_normal", h.surface_normal);
  h.local_radius_m = positiveKey(r, "local_radius_m", h.local_radius_m);
  h.local_spacing_m = positiveKey(r, "local_spacing_m", h.local_spacing_m);
  if (!(h.local_spacing_m <= 0.5 * h.local_radius_m))
    r.fail("local_spacing_m", "must be at most half of local_radius_m (" + formatNumber(h.local_radius_m) +
                                  " m): the local model needs at least two shells" + got(h.local_spacing_m));
  if (h.local_radius_m / h.local_spacing_m > 64.0)
    r.fail("local_spacing_m", "is too fine for local_radius_m (more than 64 shells: the local model would have "
                              "tens of thousands of nodes)" + got(h.local_spacing_m));
  h.blade_length_m = positiveKey(r, "blade_length_m", h.blade_length_m);
  h.blade_axis = unitKey(r, "blade_axis", h.blade_axis);
  h.record_trajectory = r.boolean("record_trajectory", h.record_trajectory);
  return h;
}

nlohmann::ordered_json hapticsSpecJson(const HapticsSpec& h) {
  using J = nlohmann::ordered_json;
  auto vec = [](const Vec3d& v) { return J::array({v.x, v.y, v.z}); };
  J j;
  j["device"] = h.device;
  if (!h.trajectory.empty()) j["trajectory"] = h.trajectory;
  j["playback"] = h.playback;
  j["udp_port"] = h.udp_port;
  j["udp_device"] = h.udp_device;
  j["openhaptics_device"] = h.openhaptics_device;
  j["workspace_scale"] = h.workspace_scale;
  j["workspace_offset_m"] = vec(h.workspace_offset_m);
  j["max_force_n"] = h.max_force_n;
  j["rate_hz"] = h.rate_hz;
  j["max_force_rate_n_per_s"] = h.max_force_rate_n_per_s;
  j["realtime"] = h.realtime;
  j["cpu"] = h.cpu;
  if (h.has_surface_point) j["surface_point_m"] = vec(h.surface_point_m);
  j["surface_normal"] = vec(h.surface_normal);
  j["local_radius_m"] = h.local_radius_m;
  j["local_spacing_m"] = h.local_spacing_m;
  j["blade_length_m"] = h.blade_length_m;
  j["blade_axis"] = vec(h.blade_axis);
  j["record_trajectory"] = h.record_trajectory;
  return j;
}

}  // namespace inc
