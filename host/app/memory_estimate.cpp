// Memory estimate of a scene from the counts it implies, and the check against what the machine offers.
#include "host/app/memory_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include "base/format_number.h"
#include "host/io/mesh.h"
#include "model/input_error.h"

namespace inc {

namespace {

// Peak bytes per unit while a model is built and its first frame runs (peak RSS over the count, CPU backend,
// float32, with a fifth more for safety; measured at 1e5-2e5 units: MLS 1075 B per particle at support_factor 2, PBD
// 4.0 KB per lattice sphere). tests/app/test_memory_estimate.cpp checks each against what the built models report.
// An MLS particle: state, moment matrices and per-pair neighbour data (about 4/3 pi support_factor^3 pairs), with the
// sampling and the neighbour search's cell lists at the peak; a PBD sphere: state, ~26 links, shape matching,
// colouring, the skin; a surface triangle: the skin's binding and the cut surface's state. float64 stores the reals
// twice as wide (the indices stay): kFloat64Factor.
constexpr double kMlsBytesPerParticle = 480.0;
constexpr double kMlsBytesPerNeighbour = 24.0;
constexpr double kPbdBytesPerSphere = 4800.0;
constexpr double kTearBytesPerParticle = 2048.0;
constexpr double kSurfaceBytesPerTriangle = 1024.0;
constexpr double kFloat64Factor = 1.7;
constexpr double kPi = 3.14159265358979323846;

struct BodySize {
  double volume_m3 = 0.0;  // the body's volume
  double triangles = 0.0;  // its surface mesh's triangles (a mesh geometry; 0: generated, small)
  double mesh_vertices = 0.0;
};

BodySize bodySize(const GeometrySpec& g) {
  BodySize b;
  switch (g.kind) {
    case GeometrySpec::Kind::Box:
    case GeometrySpec::Kind::Beam: b.volume_m3 = g.size.x * g.size.y * g.size.z; break;
    case GeometrySpec::Kind::Sphere: b.volume_m3 = 4.0 / 3.0 * kPi * g.radius * g.radius * g.radius; break;
    case GeometrySpec::Kind::Ellipsoid: b.volume_m3 = 4.0 / 3.0 * kPi * g.radii.x * g.radii.y * g.radii.z; break;
    case GeometrySpec::Kind::Mesh: {
      const MeshReport rep = analyzeMesh(loadMesh(g.mesh_path));
      const double s = g.mesh_scale;
      b.volume_m3 = std::abs(rep.signed_volume) * s * s * s;
      b.triangles = rep.triangle_count;
      b.mesh_vertices = rep.vertex_count;
      break;
    }
  }
  return b;
}

// One model's share: `count` units of `bytes_each`, sized by `key`.
struct ModelShare {
  std::string model, unit, key;
  double count = 0.0, bytes_each = 0.0;
  double bytes() const { return count * bytes_each; }
};

// The tearing sheet's particles: a box's sheet, a beam's tube, a mesh's vertices (tearingSetupFromScene).
double tearParticles(const GeometrySpec& g, const BodySize& b) {
  const double h = g.spacing;
  if (g.kind == GeometrySpec::Kind::Box) return (g.size.x / h + 1.0) * (g.size.y / h + 1.0);
  if (g.kind == GeometrySpec::Kind::Beam) return (2.0 * kPi * 0.5 * g.size.y / h) * (g.size.x / h + 1.0);
  return b.mesh_vertices;
}

std::vector<ModelShare> modelShares(const Scene& scene) {
  const GeometrySpec& g = scene.geometry;
  const double wide = scene.solver.precision == Precision::Float64 ? kFloat64Factor : 1.0;
  const BodySize body = bodySize(g);
  const double lattice = body.volume_m3 / (g.spacing * g.spacing * g.spacing);
  std::vector<ModelShare> shares;
  if (scene.models.mls) {
    const double sf = scene.mls.support_factor;
    const double neighbours = 4.0 / 3.0 * kPi * sf * sf * sf;
    shares.push_back({"mls", "particles", "geometry.spacing_m", lattice,
                      wide * (kMlsBytesPerParticle + kMlsBytesPerNeighbour * neighbours)});
  }
  if (scene.models.pbd_metaballs) {
    const bool packed = scene.pbd.target_spheres > 0;
    shares.push_back({scene.models.cutting ? "dissection" : "pbd_metaballs", "spheres",
                      packed ? "pbd.target_spheres" : "geometry.spacing_m",
                      packed ? double(scene.pbd.target_spheres) : lattice, wide * kPbdBytesPerSphere});
    if (body.triangles > 0)
      shares.push_back({"skin", "triangles", "geometry.mesh", body.triangles, kSurfaceBytesPerTriangle});
  }
  if (scene.models.tearing)
    shares.push_back(
        {"tearing_sheet", "particles", "geometry.spacing_m", tearParticles(g, body), wide * kTearBytesPerParticle});
  return shares;
}

std::string bytesText(double bytes) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  if (bytes >= double(1 << 30))
    s << bytes / double(1 << 30) << " GiB";
  else if (bytes >= double(1 << 20))
    s << bytes / double(1 << 20) << " MiB";
  else
    s << bytes / 1024.0 << " KiB";
  return s.str();
}

std::string countText(double n) {
  std::ostringstream s;
  s.precision(3);
  s << n;
  return s.str();
}

// What to do with the key that sets the size.
std::string sizeHint(const std::string& key) {
  if (key == "pbd.target_spheres") return "ask for fewer spheres with pbd.target_spheres";
  if (key == "geometry.mesh") return "use a mesh of fewer triangles in geometry.mesh";
  return "make " + key + " larger (particle and sphere counts go as 1 / spacing^3)";
}

// MemAvailable of /proc/meminfo in bytes (0: not readable).
std::size_t availableHostMemory() {
  std::ifstream in("/proc/meminfo");
  for (std::string line; std::getline(in, line);) {
    std::istringstream s(line);
    std::string name;
    std::size_t kib = 0;
    if (s >> name >> kib && name == "MemAvailable:") return kib * 1024;
  }
  return 0;
}

// What the cgroup (v2) still lets this process allocate, memory.max - memory.current (0: no limit or not readable):
// a container's limit, which /proc/meminfo does not show.
std::size_t cgroupMemoryLeft() {
  std::ifstream max_in("/sys/fs/cgroup/memory.max"), cur_in("/sys/fs/cgroup/memory.current");
  std::string max_text;
  std::size_t cur = 0;
  if (!(max_in >> max_text) || max_text == "max" || !(cur_in >> cur)) return 0;
  const std::size_t max = std::size_t(std::strtoull(max_text.c_str(), nullptr, 10));
  return max > cur ? max - cur : 1;
}

}  // namespace

SceneMemoryEstimate estimateSceneMemory(const Scene& scene, BackendKind backend) {
  SceneMemoryEstimate e;
  double host = 0.0, largest = -1.0;
  for (const ModelShare& m : modelShares(scene)) {
    host += m.bytes();
    if (m.bytes() > largest) {
      largest = m.bytes();
      e.size_key = m.key;
    }
    e.detail += (e.detail.empty() ? "" : "; ") + m.model + ": " + countText(m.count) + " " + m.unit + " x " +
                bytesText(m.bytes_each) + " = " + bytesText(m.bytes());
  }
  e.bytes.host_bytes = std::size_t(std::min(host, 1e19));
  // The CUDA backend keeps each model's arrays on the device besides the host's build.
  if (backend == BackendKind::Cuda) e.bytes.device_bytes = e.bytes.host_bytes;
  if (e.size_key.empty()) e.size_key = "geometry.spacing_m";
  return e;
}

MemoryBudget machineMemoryBudget(const BackendChoice& backend) {
  MemoryBudget b;
  b.host_bytes = availableHostMemory();
  b.host_source = "available host memory (MemAvailable)";
  const std::size_t cgroup = cgroupMemoryLeft();
  if (cgroup > 0 && (b.host_bytes == 0 || cgroup < b.host_bytes)) {
    b.host_bytes = cgroup;
    b.host_source = "memory left under this process's cgroup limit (memory.max)";
  }
  if (b.host_bytes == 0) {
    b.host_bytes = kDefaultHostMemoryCap;
    b.host_source = "the default cap (host memory unknown)";
  }
  if (const char* mib = std::getenv("INCISION_MEMORY_LIMIT_MIB")) {
    const double v = std::atof(mib);
    if (v > 0) {
      b.host_bytes = std::size_t(v * 1048576.0);
      b.host_source = "limit INCISION_MEMORY_LIMIT_MIB";
    }
  }
  if (backend.kind == BackendKind::Cuda) b.device_bytes = backend.device_memory_bytes;
  return b;
}

SceneMemoryEstimate checkSceneMemory(const Scene& scene, BackendKind backend, const MemoryBudget& budget) {
  const SceneMemoryEstimate e = estimateSceneMemory(scene, backend);
  const auto refuse = [&](std::size_t need, std::size_t have, const std::string& where) {
    throw InputError(scene.file, e.size_key,
                     "the scene needs about " + bytesText(double(need)) + " of " + where + " memory (" + e.detail +
                         "), more than the " + bytesText(double(have)) + " " +
                         (where == "host" ? budget.host_source : "the GPU has") + "; " + sizeHint(e.size_key));
  };
  if (e.bytes.host_bytes > budget.host_bytes) refuse(e.bytes.host_bytes, budget.host_bytes, "host");
  if (budget.device_bytes > 0 && e.bytes.device_bytes > budget.device_bytes)
    refuse(e.bytes.device_bytes, budget.device_bytes, "device");
  return e;
}

}  // namespace inc
