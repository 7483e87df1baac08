// Tests of the scene keys of the cutting force model (material.cutting): values reach the model, bad ones are refused.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "host/haptics/bem_global.h"
#include "host/haptics/cutting_force_model.h"
#include "host/io/mesh.h"
#include "host/scene/haptics_scene.h"
#include "host/scene/scene_loader.h"
#include "model/input_error.h"

namespace inc {
namespace {

const char* kFile = "scenes/cut_thresholds.json";

nlohmann::json sceneWithCutting(const nlohmann::json& cutting) {
  nlohmann::json j =
      nlohmann::json::parse(R"({"geometry": {"kind": "box"}, "models": {"mls": true, "haptics": true}})");
  j["material"]["cutting"] = cutting;
  return j;
}

// Parses expecting an InputError naming kFile, exactly `key`, and a reason containing `part`.
void expectRefused(const std::string& text, const std::string& key, const std::string& part) {
  try {
    parseScene(text, kFile, ".");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), kFile) << e.what();
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_NE(e.reason().find(part), std::string::npos) << e.what();
  }
}

TEST(HapticScene, CutThresholdsAreReadAndDriveTheModel) {
  const Scene s = parseScene(sceneWithCutting({{"press_threshold_n", 2.5},
                                               {"static_friction_n", 1.25},
                                               {"dynamic_friction_n", 0.5},
                                               {"friction_n_per_m", 400.0}})
                                 .dump(),
                             kFile, ".");
  EXPECT_EQ(s.cut_thresholds.press_n, 2.5);
  EXPECT_EQ(s.cut_thresholds.static_n, 1.25);
  EXPECT_EQ(s.cut_thresholds.dynamic_n, 0.5);
  EXPECT_EQ(s.cut_thresholds.friction_per_depth_n_per_m, 400.0);
  // The model uses the scene's values: a normal force of 2 N (< F_p = 2.5 N) does not let the blade in, so
  // a tangential 1.3 N (> F_s) does not cut; 2.6 N does, then 1.3 N cuts; 0.6 N (in the band) keeps cutting
  // with friction 400 N/m x 2 mm = 0.8 N; 0.49 N (< F_d) stops.
  CuttingForceModel m(s.cut_thresholds, s.file);
  const Vec3d n{0, 0, 1}, v{0.01, 0, 0};
  EXPECT_EQ(m.tick({1.3, 0, -2.0}, n, v, 2e-3).machine.state, CutState::kPressing);
  EXPECT_EQ(m.tick({0.0, 0, -2.6}, n, v, 2e-3).machine.state, CutState::kPressing);
  EXPECT_EQ(m.tick({1.3, 0, -2.6}, n, v, 2e-3).machine.state, CutState::kCutting);
  const CutForceOutput band = m.tick({0.6, 0, -2.6}, n, v, 2e-3);
  EXPECT_EQ(band.machine.state, CutState::kCutting);
  EXPECT_NEAR(band.friction_n.x, -0.8, 1e-12);
  EXPECT_EQ(m.tick({0.49, 0, -2.6}, n, v, 2e-3).machine.state, CutState::kStopped);
}

TEST(HapticScene, CutThresholdsDefaultAndRoundTrip) {
  const Scene d = parseScene(R"({"geometry": {"kind": "box"}, "models": {"mls": true}})", kFile, ".");
  const CutThresholds<double> def;
  EXPECT_EQ(d.cut_thresholds.press_n, def.press_n);
  EXPECT_EQ(d.cut_thresholds.static_n, def.static_n);
  EXPECT_EQ(d.cut_thresholds.dynamic_n, def.dynamic_n);
  EXPECT_EQ(d.cut_thresholds.friction_per_depth_n_per_m, def.friction_per_depth_n_per_m);
  // Partial object: the others keep their defaults. Written and read back exactly (1/3 N has no short form).
  const Scene s =
      parseScene(sceneWithCutting({{"static_friction_n", 1.0 / 3.0}, {"press_threshold_n", 0.0}}).dump(), kFile, ".");
  EXPECT_EQ(s.cut_thresholds.static_n, 1.0 / 3.0);
  EXPECT_EQ(s.cut_thresholds.press_n, 0.0);
  EXPECT_EQ(s.cut_thresholds.dynamic_n, def.dynamic_n);
  const Scene r = parseScene(sceneToJson(s), kFile, ".");
  EXPECT_EQ(r.cut_thresholds.press_n, s.cut_thresholds.press_n);
  EXPECT_EQ(r.cut_thresholds.static_n, s.cut_thresholds.static_n);
  EXPECT_EQ(r.cut_thresholds.dynamic_n, s.cut_thresholds.dynamic_n);
  EXPECT_EQ(r.cut_thresholds.friction_per_depth_n_per_m, s.cut_thresholds.friction_per_depth_n_per_m);
}

TEST(HapticScene, BadCutThresholdsNameFileAndKey) {
  const std::string k = "material.cutting.";
  // NaN: as a JSON literal (not JSON) and as a string.
  expectRefused(R"({"geometry": {"kind": "box"}, "models": {"mls": true},
                    "material": {"cutting": {"static_friction_n": NaN}}})",
                k + "static_friction_n", "NaN");
  expectRefused(sceneWithCutting({{"dynamic_friction_n", "nan"}}).dump(), k + "dynamic_friction_n", "NaN");
  // Negative values.
  expectRefused(sceneWithCutting({{"press_threshold_n", -0.1}}).dump(), k + "press_threshold_n", ">= 0");
  expectRefused(sceneWithCutting({{"static_friction_n", -1.0}}).dump(), k + "static_friction_n", "> 0");
  expectRefused(sceneWithCutting({{"dynamic_friction_n", -0.2}}).dump(), k + "dynamic_friction_n", "> 0");
  expectRefused(sceneWithCutting({{"friction_n_per_m", -5.0}}).dump(), k + "friction_n_per_m", ">= 0");
  // F_d above (and equal to) F_s: no hysteresis.
  expectRefused(sceneWithCutting({{"static_friction_n", 0.6}, {"dynamic_friction_n", 0.8}}).dump(),
                k + "dynamic_friction_n", "below static friction F_s = 0.6 N");
  expectRefused(sceneWithCutting({{"static_friction_n", 0.6}, {"dynamic_friction_n", 0.6}}).dump(),
                k + "dynamic_friction_n", "below static friction");
  // Unknown key (typo) and a wrong type.
  expectRefused(sceneWithCutting({{"static_friction", 0.6}}).dump(), k + "static_friction", "did you mean");
  expectRefused(sceneWithCutting({{"press_threshold_n", "1"}}).dump(), k + "press_threshold_n", "expected a number");
}

nlohmann::json sceneWithHaptics(const nlohmann::json& haptics) {
  nlohmann::json j =
      nlohmann::json::parse(R"({"geometry": {"kind": "box"}, "models": {"mls": true, "haptics": true}})");
  j["haptics"] = haptics;
  return j;
}

// The haptics section: every key read (the trajectory resolved against the scene's folder and loaded once to
// check it), written and read back to the same values; absent keys keep the defaults.
TEST(HapticScene, HapticsKeysAreReadAndRoundTrip) {
  const auto dir = std::filesystem::temp_directory_path() / ("incision_haptics_keys_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "stroke.traj") << "0 0 0 0.02 1 0 0 0 0\n0.5 0.01 0 0.01 1 0 0 0 1\n";
  const std::string scene_file = (dir / "scene.json").string();
  const Scene s = parseScene(sceneWithHaptics({{"device", "scripted"},
                                               {"name", "right"},
                                               {"trajectory", "stroke.traj"},
                                               {"playback", "tick"},
                                               {"udp_port", 47123},
                                               {"udp_device", 3},
                                               {"max_force_n", 2.5},
                                               {"rate_hz", 2000},
                                               {"max_force_rate_n_per_s", 500},
                                               {"realtime", false},
                                               {"cpu", 1},
                                               {"surface_point_m", {0, 0, 0.03}},
                                               {"surface_normal", {0, 0, 2}},
                                               {"local_radius_m", 0.01},
                                               {"local_spacing_m", 0.0025},
                                               {"blade_length_m", 0.04},
                                               {"blade_axis", {1, 0, 0}},
                                               {"record_trajectory", true}})
                                 .dump(),
                             scene_file, dir.string());
  ASSERT_EQ(s.haptics.devices.size(), 1u);
  EXPECT_FALSE(s.haptics.devices_listed);
  const HapticsSpec& hs = s.haptics;
  const HapticDeviceSpec& h = s.haptics.devices[0];
  EXPECT_EQ(h.trajectory, (dir / "stroke.traj").lexically_normal().string());
  EXPECT_EQ(h.playback, "tick");
  EXPECT_EQ(h.udp_port, 47123);
  EXPECT_EQ(h.udp_device, 3);
  EXPECT_EQ(h.max_force_n, 2.5);
  EXPECT_EQ(h.rate_hz, 2000.0);
  EXPECT_FALSE(h.realtime);
  EXPECT_EQ(h.cpu, 1);
  EXPECT_TRUE(hs.has_surface_point);
  EXPECT_EQ(hs.surface_point_m.z, 0.03);
  EXPECT_EQ(hs.surface_normal.z, 1.0);  // normalised
  EXPECT_EQ(hs.local_spacing_m, 0.0025);
  EXPECT_EQ(h.blade_axis.x, 1.0);
  EXPECT_TRUE(hs.record_trajectory);
  const Scene r = parseScene(sceneToJson(s), scene_file, dir.string());
  EXPECT_EQ(sceneToJson(r), sceneToJson(s));
  EXPECT_EQ(r.haptics.devices[0].trajectory, h.trajectory);
  EXPECT_EQ(r.haptics.devices[0].name, "right");
  EXPECT_EQ(r.haptics.local_radius_m, hs.local_radius_m);
  const Scene d = parseScene(R"({"geometry": {"kind": "box"}, "models": {"mls": true}})", kFile, ".");
  ASSERT_EQ(d.haptics.devices.size(), 1u);
  EXPECT_EQ(d.haptics.devices[0].device, "scripted");
  EXPECT_EQ(d.haptics.devices[0].rate_hz, 1000.0);
  EXPECT_EQ(d.haptics.devices[0].tool, "auto");
  EXPECT_EQ(d.haptics.global_model, "none");
  EXPECT_FALSE(d.haptics.has_surface_point);
  EXPECT_EQ(parseScene(sceneToJson(d), kFile, ".").haptics.devices[0].rate_hz, 1000.0);
  std::filesystem::remove_all(dir);
}

TEST(HapticScene, BadHapticsKeysNameFileAndKey) {
  const std::string k = "haptics.";
  expectRefused(sceneWithHaptics({{"device", "phantom"}}).dump(), k + "device", "expected one of");
  if (!openHapticsBuilt())
    expectRefused(sceneWithHaptics({{"device", "openhaptics"}}).dump(), k + "device", "not built");
  expectRefused(sceneWithHaptics({{"trajectory", "no_such_stroke.traj"}}).dump(), k + "trajectory",
                "cannot open trajectory file");
  expectRefused(sceneWithHaptics({{"trajectory", ""}}).dump(), k + "trajectory", "must name");
  expectRefused(sceneWithHaptics({{"playback", "bytime"}}).dump(), k + "playback", "expected one of");
  expectRefused(sceneWithHaptics({{"udp_port", 0}}).dump(), k + "udp_port", "[1, 65535]");
  expectRefused(sceneWithHaptics({{"udp_port", 70000}}).dump(), k + "udp_port", "[1, 65535]");
  expectRefused(sceneWithHaptics({{"udp_device", -1}}).dump(), k + "udp_device", "[0, 65535]");
  expectRefused(sceneWithHaptics({{"max_force_n", 0}}).dump(), k + "max_force_n", "> 0");
  expectRefused(sceneWithHaptics({{"rate_hz", 50}}).dump(), k + "rate_hz", "[100, 10000]");
  expectRefused(sceneWithHaptics({{"rate_hz", "nan"}}).dump(), k + "rate_hz", "NaN");
  expectRefused(sceneWithHaptics({{"max_force_rate_n_per_s", -1}}).dump(), k + "max_force_rate_n_per_s", "> 0");
  expectRefused(sceneWithHaptics({{"cpu", -2}}).dump(), k + "cpu", "[-1, 4095]");
  expectRefused(sceneWithHaptics({{"surface_normal", {0, 0, 0}}}).dump(), k + "surface_normal", "non-zero");
  expectRefused(sceneWithHaptics({{"local_radius_m", -0.01}}).dump(), k + "local_radius_m", "> 0");
  expectRefused(sceneWithHaptics({{"local_spacing_m", 0.005}}).dump(), k + "local_spacing_m", "at most half");
  expectRefused(sceneWithHaptics({{"local_spacing_m", 1e-5}}).dump(), k + "local_spacing_m", "too fine");
  expectRefused(sceneWithHaptics({{"blade_length_m", 0}}).dump(), k + "blade_length_m", "> 0");
  expectRefused(sceneWithHaptics({{"blade_axis", {0, 0, 0}}}).dump(), k + "blade_axis", "non-zero");
  expectRefused(sceneWithHaptics({{"rate", 1000}}).dump(), k + "rate", "did you mean");
  expectRefused(sceneWithHaptics({{"realtime", 1}}).dump(), k + "realtime", "expected a boolean");
  // A trajectory file with a bad line: the scene key, and the file and line in the reason.
  const auto dir = std::filesystem::temp_directory_path() / ("incision_haptics_bad_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "bad.traj") << "0 0 0 0 1 0 0 0 0\n0.1 0 0 zero 1 0 0 0 0\n";
  try {
    parseScene(sceneWithHaptics({{"trajectory", "bad.traj"}}).dump(), kFile, dir.string());
    ADD_FAILURE() << "accepted a bad trajectory";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), kFile);
    EXPECT_EQ(e.key(), k + "trajectory");
    EXPECT_NE(e.reason().find("bad.traj"), std::string::npos) << e.what();
    EXPECT_NE(e.reason().find("line 2"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

// Two hands: haptics.devices lists each device's keys (name, driver, rate, tool, ...); the tissue keys stay shared.
// Every key is read, the trajectories resolved against the scene's folder, and the list form is written back as a
// list (sceneToJson reads back to the same text); devices without a name are hand0, hand1, ...
TEST(HapticScene, DevicesListIsReadAndRoundTrips) {
  const auto dir = std::filesystem::temp_directory_path() / ("incision_haptics_devices_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "left.traj") << "0 0 0 0.02 1 0 0 0 0\n";
  std::ofstream(dir / "right.traj") << "0 0.01 0 0.02 1 0 0 0 0\n";
  const std::string scene_file = (dir / "scene.json").string();
  const Scene s = parseScene(
      sceneWithHaptics(
          {{"devices",
            {{{"name", "left"}, {"trajectory", "left.traj"}, {"rate_hz", 1000}, {"tool", "probe"}},
             {{"trajectory", "right.traj"}, {"playback", "tick"}, {"rate_hz", 500}, {"cpu", 1}, {"max_force_n", 2.0}}}},
           {"local_radius_m", 0.01},
           {"record_trajectory", true}})
          .dump(),
      scene_file, dir.string());
  const HapticsSpec& h = s.haptics;
  EXPECT_TRUE(h.devices_listed);
  ASSERT_EQ(h.devices.size(), 2u);
  EXPECT_EQ(h.devices[0].name, "left");
  EXPECT_EQ(h.devices[0].trajectory, (dir / "left.traj").lexically_normal().string());
  EXPECT_EQ(h.devices[0].tool, "probe");
  EXPECT_EQ(h.devices[0].rate_hz, 1000.0);
  EXPECT_EQ(h.devices[1].name, "hand1");
  EXPECT_EQ(h.devices[1].trajectory, (dir / "right.traj").lexically_normal().string());
  EXPECT_EQ(h.devices[1].playback, "tick");
  EXPECT_EQ(h.devices[1].rate_hz, 500.0);
  EXPECT_EQ(h.devices[1].cpu, 1);
  EXPECT_EQ(h.devices[1].max_force_n, 2.0);
  EXPECT_EQ(h.devices[1].tool, "auto");
  EXPECT_EQ(h.local_radius_m, 0.01);
  EXPECT_TRUE(h.record_trajectory);
  EXPECT_EQ(hapticDeviceKey(h, 1, "trajectory"), "haptics.devices[1].trajectory");
  const std::string text = sceneToJson(s);
  EXPECT_NE(text.find("\"devices\""), std::string::npos);
  const Scene r = parseScene(text, scene_file, dir.string());
  EXPECT_EQ(sceneToJson(r), text);
  ASSERT_EQ(r.haptics.devices.size(), 2u);
  EXPECT_EQ(r.haptics.devices[1].name, "hand1");
  EXPECT_EQ(r.haptics.devices[1].rate_hz, 500.0);
  // The single-device form stays what it was: its keys in `haptics`, written back flat.
  EXPECT_EQ(hapticDeviceKey(parseScene(sceneWithHaptics({{"rate_hz", 500}}).dump(), kFile, ".").haptics, 0, "rate_hz"),
            "haptics.rate_hz");
  std::filesystem::remove_all(dir);
}

// Bad input in the list form names the file and the device's key path (haptics.devices[1].trajectory), and the
// checks between devices (names, UDP ports, one scalpel) name the later device.
TEST(HapticScene, BadDevicesNameTheDevicesKeyPath) {
  const std::string k = "haptics.devices";
  auto two = [](const nlohmann::json& a, const nlohmann::json& b) {
    return sceneWithHaptics({{"devices", {a, b}}}).dump();
  };
  const nlohmann::json ok = {{"device", "udp"}, {"udp_port", 47001}};
  expectRefused(two(ok, {{"device", "scripted"}, {"trajectory", "no_such_stroke.traj"}}), k + "[1].trajectory",
                "cannot open trajectory file");
  expectRefused(two(ok, {{"rate_hz", 50}}), k + "[1].rate_hz", "[100, 10000]");
  expectRefused(two(ok, {{"tool", "grasper"}}), k + "[1].tool", "expected one of");
  expectRefused(two(ok, {{"rate", 1000}}), k + "[1].rate", "did you mean");
  expectRefused(two(ok, {{"surface_normal", {0, 0, 1}}}), k + "[1].surface_normal", "shared by every device");
  expectRefused(two({{"name", "left"}, {"device", "udp"}}, {{"name", "left"}, {"device", "udp"}, {"udp_port", 47002}}),
                k + "[1].name", "already the name of haptics.devices[0]");
  expectRefused(two({{"name", "a b"}}, ok), k + "[0].name", "letters, digits");
  expectRefused(two(ok, {{"device", "udp"}, {"udp_port", 47001}}), k + "[1].udp_port", "already the port of");
  expectRefused(two(ok, {{"device", "udp"}, {"udp_port", 47002}, {"tool", "scalpel"}}), k + "[1].tool",
                "needs models.cutting");
  // A key of one device next to the list: which device would it belong to?
  expectRefused(sceneWithHaptics({{"devices", {ok}}, {"rate_hz", 1000}}).dump(), "haptics.rate_hz",
                "belongs in each entry of haptics.devices");
  expectRefused(sceneWithHaptics({{"devices", nlohmann::json::array()}}).dump(), "haptics.devices", "1 to 4 devices");
  expectRefused(sceneWithHaptics({{"devices", {ok, ok, ok, ok, ok}}}).dump(), "haptics.devices", "1 to 4 devices");
  expectRefused(sceneWithHaptics({{"devices", {1, 2}}}).dump(), "haptics.devices[0]", "expected an object");
  // Two scalpels on a model that can be cut: the dissection model cuts one stroke at a time.
  nlohmann::json j = nlohmann::json::parse(
      R"({"geometry": {"kind": "box"}, "models": {"pbd_metaballs": true, "cutting": true, "haptics": true}})");
  j["haptics"]["devices"] = {{{"device", "udp"}, {"tool", "scalpel"}},
                             {{"device", "udp"}, {"udp_port", 47002}, {"tool", "scalpel"}}};
  expectRefused(j.dump(), k + "[1].tool", "only one device may hold the scalpel");
}

// global_model "bem": the organ mesh is resolved against the scene's folder, loaded and checked, its cache defaults
// to the scene file's name with .bemcache beside it, and the keys read back to the same values.
TEST(HapticScene, GlobalModelKeysAreReadCheckedAndRoundTrip) {
  const auto dir = std::filesystem::temp_directory_path() / ("incision_haptics_global_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  writeObj((dir / "organ.obj").string(), icosphereMesh(0.05, 1));
  const std::string scene_file = (dir / "touch.json").string();
  nlohmann::json j = sceneWithHaptics({{"global_model", "bem"}, {"global_mesh", "organ.obj"}});
  j["fixed"] = {{{"min_m", {-1, -1, -1}}, {"max_m", {1, 1, -0.035}}}};
  const Scene s = parseScene(j.dump(), scene_file, dir.string());
  EXPECT_EQ(s.haptics.global_model, "bem");
  EXPECT_EQ(s.haptics.global_mesh, (dir / "organ.obj").lexically_normal().string());
  EXPECT_EQ(s.haptics.global_mesh_scale, 1.0);
  EXPECT_EQ(s.haptics.global_cache, (dir / "touch.bemcache").lexically_normal().string());
  const Scene r = parseScene(sceneToJson(s), scene_file, dir.string());
  EXPECT_EQ(sceneToJson(r), sceneToJson(s));
  EXPECT_EQ(r.haptics.global_cache, s.haptics.global_cache);

  auto refused = [&](nlohmann::json scene, const std::string& key, const std::string& part) {
    try {
      parseScene(scene.dump(), kFile, dir.string());
      ADD_FAILURE() << "accepted: " << scene.dump();
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), kFile) << e.what();
      EXPECT_EQ(e.key(), key) << e.what();
      EXPECT_NE(e.reason().find(part), std::string::npos) << e.what();
    }
  };
  const std::string k = "haptics.";
  nlohmann::json bad = j;
  bad.erase("fixed");
  refused(bad, k + "global_mesh", "no element centroid lies in a fixed region");
  bad = j;
  bad["haptics"].erase("global_mesh");
  refused(bad, k + "global_mesh", "is required");
  bad = j;
  bad["haptics"]["global_model"] = "none";
  refused(bad, k + "global_mesh", "only with global_model \"bem\"");
  bad["haptics"]["global_model"] = "fem";
  refused(bad, k + "global_model", "expected one of");
  bad = j;
  bad["haptics"]["global_mesh_scale"] = 0;
  refused(bad, k + "global_mesh_scale", "> 0");
  bad["haptics"]["global_mesh_scale"] = 1;
  bad["haptics"]["global_cache"] = "";
  refused(bad, k + "global_cache", "must name a file");
  TriangleMesh open = icosphereMesh(0.05, 1);
  open.triangles.pop_back();
  writeObj((dir / "open.obj").string(), open);
  bad = j;
  bad["haptics"]["global_mesh"] = "open.obj";
  refused(bad, k + "global_mesh", "closed");
  writeObj((dir / "fine.obj").string(), icosphereMesh(0.05, 4));  // 5120 triangles
  bad["haptics"]["global_mesh"] = "fine.obj";
  refused(bad, k + "global_mesh", "more than the 1500");
  bad["haptics"]["global_mesh"] = "absent.obj";
  refused(bad, k + "global_mesh", "absent.obj");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace inc
