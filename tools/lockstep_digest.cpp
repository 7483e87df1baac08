// Prints a per-frame digest of a lockstep haptic cutting session (CPU, float64): the bit-exactness check of refactors.
//
// tools/check-outputs runs this program from the build before and after a change and compares the two outputs
// line for line. The session is built from a haptics scene (scenes/haptic_cut_block.json by default) the way
// SceneHaptics builds its scalpel hand (tissue plane, MFS tip stiffness, cutting thresholds, blade, loop rate),
// but runs in lockstep (HapticCutSession: ticks on this thread, a FakeClock), so the output does not depend on
// the machine's timing. Positions are hashed as raw bytes: a change in the last bit of one coordinate shows.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "host/haptics/haptic_cut_session.h"
#include "host/haptics/scene_haptics.h"
#include "host/haptics/tip_contact.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "host/sim/dissection_simulation.h"
#include "model/input_error.h"

namespace {

using namespace inc;

#ifndef INCISION_SOURCE_DIR
#define INCISION_SOURCE_DIR "."
#endif

constexpr std::uint64_t kFnvOffset = 1469598103934665603ull;

std::uint64_t fnv1a(const void* data, std::size_t n, std::uint64_t h) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

struct Options {
  std::string scene = std::string(INCISION_SOURCE_DIR) + "/scenes/haptic_cut_block.json";
  int frames = 0;  // 0: the scene's duration_s / frame_dt_s
};

void printHelp(const char* argv0) {
  std::printf(
      "usage: %s [SCENE] [--frames N]\n"
      "\n"
      "Runs the scene's haptic scalpel (its first device, a scripted trajectory) against its cutting model in a\n"
      "lockstep HapticCutSession on the CPU backend in float64 (the scene's backend and precision are ignored),\n"
      "and prints one line per frame:\n"
      "  frame F ticks T positions H triangles_hash H forces H surface_triangles N spheres N links N cuts N\n"
      "  cut_events N state S\n"
      "(positions: FNV-1a of the bytes of every particle and surface-vertex position; triangles_hash: of the\n"
      "surface's vertex indices; forces: of the model and sent force of each haptic tick of the frame; state: the\n"
      "cutting tool's state after the frame), then `total frames N ticks N hash H` (FNV-1a of every frame line).\n"
      "The same build gives the same output on every run; compare two builds' outputs to prove a refactor\n"
      "changed nothing (tools/check-outputs does).\n"
      "\n"
      "  SCENE       a scene with models.cutting and models.haptics (default: %s)\n"
      "  --frames N  frames to run (default: the scene's duration_s / solver.frame_dt_s, rounded)\n"
      "  --help      this text\n",
      argv0, Options{}.scene.c_str());
}

// Returns false (after a message) for arguments it does not understand.
bool parseArgs(int argc, char** argv, Options& opt, bool& help) {
  bool have_scene = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      help = true;
    } else if (a == "--frames" && i + 1 < argc) {
      char* end = nullptr;
      const long n = std::strtol(argv[++i], &end, 10);
      if (*end != '\0' || n <= 0 || n > 1000000) {
        std::fprintf(stderr, "--frames: expected a positive integer, got \"%s\"\n", argv[i]);
        return false;
      }
      opt.frames = int(n);
    } else if (!a.empty() && a[0] != '-' && !have_scene) {
      opt.scene = a;
      have_scene = true;
    } else {
      std::fprintf(stderr, "unexpected argument \"%s\" (see --help)\n", a.c_str());
      return false;
    }
  }
  return true;
}

const char* cutStateName(CutState s) {
  switch (s) {
    case CutState::kIdle: return "idle";
    case CutState::kPressing: return "pressing";
    case CutState::kCutting: return "cutting";
    case CutState::kStopped: return "stopped";
  }
  return "unknown";
}

// The scalpel's loop as SceneHaptics configures it, lockstep: no thread, so no realtime scheduling; the
// recording holds every tick of the run, since the session reads the newest record for the blade's Drag pose.
HapticLoopConfig lockstepLoopConfig(const Scene& scene, const HapticDeviceSpec& device, int frames) {
  HapticLoopConfig c;
  c.rate_hz = device.rate_hz;
  c.max_force_rate_n_per_s = device.max_force_rate_n_per_s;
  c.stall_after_s = std::max(2.0 * scene.solver.frame_dt, 1.0 / 30.0);
  c.realtime = false;
  const double ticks_per_frame = std::ceil(scene.solver.frame_dt * device.rate_hz) + 1.0;
  c.record_capacity = std::size_t(frames) * std::size_t(ticks_per_frame);
  return c;
}

// One frame's line: the model's state after it and the haptic ticks that ran before it.
struct FrameDigest {
  std::uint64_t ticks = 0;
  std::uint64_t positions = kFnvOffset, triangles = kFnvOffset, forces = kFnvOffset;
  std::size_t surface_triangles = 0, spheres = 0, links = 0;
  int cuts = 0, cut_events = 0;
  CutState state = CutState::kIdle;
};

FrameDigest digestFrame(const SimulationModel& sim, const HapticCutSession& session, const CuttingTool& tool,
                        std::size_t first_tick) {
  const SessionFrame& frame = session.frames().back();
  FrameDigest d;
  d.ticks = frame.ticks_done;
  d.spheres = sim.particleCount();
  d.links = frame.topology.links;
  d.cuts = frame.topology.cuts_applied;
  d.cut_events = frame.cut_events;
  d.state = tool.state();
  std::vector<Vec3d> x;
  sim.currentPositions(x);
  d.positions = fnv1a(x.data(), x.size() * sizeof(Vec3d), d.positions);
  TriangleMesh surface;
  if (sim.currentSurface(surface)) {
    d.surface_triangles = surface.triangles.size();
    d.positions = fnv1a(surface.vertices.data(), surface.vertices.size() * sizeof(Vec3d), d.positions);
    d.triangles = fnv1a(surface.triangles.data(), surface.triangles.size() * sizeof(surface.triangles[0]), d.triangles);
  }
  const std::vector<TickRecord>& ticks = session.loop().records();
  for (std::size_t i = first_tick; i < ticks.size(); ++i) {
    d.forces = fnv1a(&ticks[i].model_force_n, sizeof(Vec3d), d.forces);
    d.forces = fnv1a(&ticks[i].force_n, sizeof(Vec3d), d.forces);
  }
  return d;
}

std::string formatFrame(int index, const FrameDigest& d) {
  char line[512];
  std::snprintf(line, sizeof line,
                "frame %d ticks %llu positions %016llx triangles_hash %016llx forces %016llx surface_triangles %zu "
                "spheres %zu links %zu cuts %d cut_events %d state %s",
                index, static_cast<unsigned long long>(d.ticks), static_cast<unsigned long long>(d.positions),
                static_cast<unsigned long long>(d.triangles), static_cast<unsigned long long>(d.forces),
                d.surface_triangles, d.spheres, d.links, d.cuts, d.cut_events, cutStateName(d.state));
  return line;
}

// Runs the session frame by frame, printing each frame's line; returns the process exit status.
int runDigest(const Options& opt) {
  const Scene scene = loadSceneFile(opt.scene);
  if (!scene.models.cutting || !scene.models.haptics)
    throw InputError(scene.file, "models", "lockstep_digest needs a scene with models.cutting and models.haptics");
  const HapticDeviceSpec& hand = scene.haptics.devices.at(0);
  const int frames =
      opt.frames > 0 ? opt.frames : std::max(1, int(std::lround(scene.duration / scene.solver.frame_dt)));

  auto sim = makeDissectionSimulation(compileScene(scene), BackendKind::Cpu, Precision::Float64);
  const std::unique_ptr<HapticDevice> device = makeSceneHapticDevice(compileScene(scene), 0);
  const TissuePlane plane = sceneTissuePlane(compileScene(scene), *sim);
  const TipStiffness tip =
      mfsTipStiffness(scene.material, scene.haptics.local_radius_m, scene.haptics.local_spacing_m, plane.normal);
  CuttingTool tool(tipElastic(tip), scene.cut_thresholds, plane.point_m, plane.normal);
  HapticCutSessionConfig cfg;
  cfg.frame_dt_s = scene.solver.frame_dt;
  cfg.blade_length_m = hand.blade_length_m;
  cfg.blade_axis_device = hand.blade_axis;
  cfg.loop = lockstepLoopConfig(scene, hand, frames);
  HapticCutSession session(*sim, *device, tool, cfg);

  std::printf("# lockstep_digest: scene %s, backend cpu, float64, %d frames of %d ticks\n", scene.name.c_str(), frames,
              session.ticksPerFrame());
  std::uint64_t total = kFnvOffset;
  for (int f = 0; f < frames; ++f) {
    const std::size_t first_tick = session.loop().records().size();
    session.runFrames(1);
    const std::string line = formatFrame(f, digestFrame(*sim, session, tool, first_tick));
    total = fnv1a(line.data(), line.size(), total);
    std::printf("%s\n", line.c_str());
  }
  for (const std::string& m : session.messages()) std::printf("refused tool event: %s\n", m.c_str());
  std::printf("total frames %d ticks %zu hash %016llx\n", frames, session.loop().records().size(),
              static_cast<unsigned long long>(total));
  return session.messages().empty() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  bool help = false;
  if (!parseArgs(argc, argv, opt, help)) return 2;
  if (help) {
    printHelp(argv[0]);
    return 0;
  }
  try {
    return runDigest(opt);
  } catch (const inc::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
