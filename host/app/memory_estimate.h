// What a scene will need in memory before it is built, and the refusal of a scene that will not fit.
#pragma once

#include <cstddef>
#include <string>

#include "host/backends/backend_choice.h"
#include "host/scene/scene.h"
#include "model/stage_timing.h"

namespace inc {

// The bytes a scene's models need at their build's peak (particles, neighbour lists, constraints, models, the skin),
// from the counts the scene implies, before anything is sampled or allocated.
struct SceneMemoryEstimate {
  MemoryReport bytes;    // host (always: the CPU builds every model) and device (a CUDA backend's copies)
  std::string size_key;  // the key that sets the largest model's size (geometry.spacing_m, pbd.target_spheres)
  std::string detail;    // per model: "mls: 3.9e+07 particles x 1.4 KiB", joined by "; "
};

// The estimate for `scene` on `backend` (Cpu or Cuda, resolved). A mesh geometry's mesh is read for its volume.
SceneMemoryEstimate estimateSceneMemory(const Scene& scene, BackendKind backend);

// What the machine offers: the host's available memory (MemAvailable of /proc/meminfo; where that cannot be read,
// kDefaultHostMemoryCap; less where a cgroup limit leaves less; INCISION_MEMORY_LIMIT_MIB replaces it) and, for the
// CUDA backend, the device's global memory (0: unknown, not checked).
struct MemoryBudget {
  std::size_t host_bytes = 0;
  std::size_t device_bytes = 0;
  std::string host_source;  // where host_bytes came from, for the message
};
inline constexpr std::size_t kDefaultHostMemoryCap = std::size_t(16) << 30;  // 16 GiB
MemoryBudget machineMemoryBudget(const BackendChoice& backend);

// Throws InputError(scene.file, estimate.size_key, ...) when the estimate exceeds the budget: the bytes needed and
// offered, per model, and what to change; else returns the estimate (validate prints it: a mesh is read once).
// `validate` and `run` call it before building anything.
SceneMemoryEstimate checkSceneMemory(const Scene& scene, BackendKind backend, const MemoryBudget& budget);

}  // namespace inc
