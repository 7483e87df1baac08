// Scene keys of the haptic loops: haptics.{devices[i].*, surface_*, local_*, record_trajectory, global_*}.
#include "host/scene/haptics_scene.h"

#include <algorithm>
#include <cctype>

#include "host/io/trajectory.h"
#include "host/scene/global_organ_mesh.h"
#include "host/scene/scene_fields.h"
#include "host/scene/scene_keys.h"
#include "model/input_error.h"

namespace inc {

namespace {

using scene_json::formatNumber;
using scene_json::ObjectReader;

constexpr std::size_t kMaxDevices = 4;

// Keys of one device (the single-device form has them in `haptics`, the list form in each devices[i]) and keys
// of the section shared by every device (host/scene/scene_keys.cpp).
const std::vector<std::string>& deviceKeys() {
  static const std::vector<std::string> k = sceneKeysUnder("haptics.devices[]");
  return k;
}
const std::vector<std::string>& sharedKeys() {
  static const std::vector<std::string> k = sceneKeysUnder("haptics");
  return k;
}
bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

std::string got(double v) { return " (got " + formatNumber(v) + ")"; }

bool validName(const std::string& n) {
  if (n.empty() || n.size() > 32) return false;
  for (char c : n)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}

// The keys of one device from `r` (the `haptics` object itself or one of its devices[i]): the table reads them,
// then the name, the driver and the trajectory file are checked here.
HapticDeviceSpec readDevice(const ObjectReader& r, const std::string& base_dir, const std::string& default_name) {
  HapticDeviceSpec d;
  d.name = default_name;
  readSceneKeys(r, "haptics.devices[]", d);
  if (r.has("name") && !validName(d.name))
    r.fail("name", "must be 1 to 32 letters, digits, '_' or '-' (it names the device's output files)");
  if (d.device == "openhaptics" && !openHapticsBuilt())
    r.fail("device",
           "the OpenHaptics driver is not built (CMake did not find the SDK: HD/hd.h and libHD; see "
           "docs/haptics.md); use \"udp\" with an external driver");
  if (r.has("trajectory")) {
    const std::string rel = r.string("trajectory", "");
    if (rel.empty()) r.fail("trajectory", "must name a trajectory file");
    d.trajectory = scene_json::resolvePath(rel, base_dir);
    try {
      (void)loadTrajectory(d.trajectory);  // checked once here: the run reads it again
    } catch (const InputError& e) {
      r.fail("trajectory", e.what());
    }
  }
  return d;
}

// Checks between the devices of the list form: names, ports, one OpenHaptics device, one scalpel.
void checkDevices(const HapticsSpec& h, const ObjectReader& r, const ModelsSpec& models) {
  const std::string list = r.keyPath("devices");
  int scalpels = 0;
  for (std::size_t i = 0; i < h.devices.size(); ++i) {
    const HapticDeviceSpec& d = h.devices[i];
    auto fail = [&](const std::string& key, const std::string& reason) {
      throw InputError(r.file(), hapticDeviceKey(h, i, key), reason);
    };
    if (d.tool == "scalpel" && !models.cutting)
      fail("tool", "\"scalpel\" needs models.cutting (a model the blade can cut); use \"probe\" or \"auto\"");
    if (d.tool == "scalpel" && ++scalpels > 1)
      fail("tool", "only one device may hold the scalpel: the dissection model cuts one stroke at a time");
    for (std::size_t j = 0; j < i; ++j) {
      const HapticDeviceSpec& e = h.devices[j];
      const std::string other = scene_json::indexPath(list, j);
      if (d.name == e.name) fail("name", "\"" + d.name + "\" is already the name of " + other);
      if (d.device == "udp" && e.device == "udp" && d.udp_port == e.udp_port)
        fail("udp_port", std::to_string(d.udp_port) + " is already the port of " + other + " (one socket per device)");
      if (d.device == "openhaptics" && e.device == "openhaptics")
        fail("device", "a second OpenHaptics device (" + other +
                           " is one): the HD scheduler is process-wide and "
                           "two devices on it are not written (docs/haptics.md)");
    }
  }
}

}  // namespace

bool openHapticsBuilt() {
#if INCISION_HAVE_OPENHAPTICS
  return true;
#else
  return false;
#endif
}

HapticsSpec readHapticsSpec(const ObjectReader& top, const std::string& base_dir, const ModelsSpec& models,
                            const std::vector<FixedRegion>& fixed) {
  HapticsSpec h;
  if (!top.has("haptics")) return h;
  const ObjectReader r = top.object("haptics");
  std::vector<std::string> known = sharedKeys();
  known.insert(known.end(), deviceKeys().begin(), deviceKeys().end());
  r.allowOnly(known);
  if (const nlohmann::json* list = r.array("devices")) {
    for (const std::string& k : deviceKeys())
      if (r.has(k))
        r.fail(k,
               "belongs in each entry of haptics.devices when the list is given (the single-device form has it "
               "here)");
    if (list->empty() || list->size() > kMaxDevices)
      r.fail("devices",
             "must list 1 to " + std::to_string(kMaxDevices) + " devices (got " + std::to_string(list->size()) + ")");
    h.devices.clear();
    h.devices_listed = true;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const ObjectReader d((*list)[i], r.file(), scene_json::indexPath(r.keyPath("devices"), i));
      for (const auto& [k, v] : d.value().items()) {
        (void)v;
        if (contains(sharedKeys(), k))
          d.fail(k, "is shared by every device: it belongs in haptics, not in haptics.devices[i]");
      }
      d.allowOnly(deviceKeys());
      h.devices.push_back(readDevice(d, base_dir, "hand" + std::to_string(i)));
    }
  } else {
    h.devices = {readDevice(r, base_dir, "")};
  }
  checkDevices(h, r, models);
  readSceneKeys(r, "haptics", h);  // the keys every device shares
  h.has_surface_point = r.has("surface_point_m");
  if (!(h.local_spacing_m <= 0.5 * h.local_radius_m))
    r.fail("local_spacing_m", "must be at most half of local_radius_m (" + formatNumber(h.local_radius_m) +
                                  " m): the local model needs at least two shells" + got(h.local_spacing_m));
  if (h.local_radius_m / h.local_spacing_m > 64.0)
    r.fail("local_spacing_m",
           "is too fine for local_radius_m (more than 64 shells: the local model would have "
           "tens of thousands of nodes)" +
               got(h.local_spacing_m));
  readGlobalModelKeys(r, base_dir, fixed, h);  // host/scene/global_organ_mesh.h
  return h;
}

}  // namespace inc
