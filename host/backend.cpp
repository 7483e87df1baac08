// Resolves --backend auto|cuda|cpu against what this build and this machine can run.
#include "host/backend.h"

#include "host/input_error.h"
#include "kernels/device_info.h"

namespace inc {

BackendKind parseBackend(const std::string& text, const std::string& file, const std::string& key) {
  if (text == "auto") return BackendKind::Auto;
  if (text == "cuda" || text == "gpu") return BackendKind::Cuda;
  if (text == "cpu") return BackendKind::Cpu;
  throw InputError(file, key, "unknown backend '" + text + "' (expected auto, cuda or cpu)");
}

const char* backendName(BackendKind k) {
  switch (k) {
    case BackendKind::Auto: return "auto";
    case BackendKind::Cuda: return "cuda";
    case BackendKind::Cpu: return "cpu";
  }
  return "?";
}

const char* precisionName(Precision p) { return p == Precision::Float64 ? "float64" : "float32"; }

BackendChoice resolveBackend(BackendKind requested) {
  BackendChoice c;
  if (requested == BackendKind::Cpu) {
    c.kind = BackendKind::Cpu;
    c.note = "backend: cpu (requested)";
    return c;
  }
  // Queried once per process: cudaGetDeviceProperties costs ~1 ms, and a cut resolves the backend at every
  // MLS rebuild (every frame the blade enters spheres). The devices a process sees do not change while it runs.
  static const cuda::DeviceReport dev = cuda::queryDevices();
  const bool usable = dev.compiled && dev.device_count > 0;
  if (usable) {
    c.kind = BackendKind::Cuda;
    c.note = "backend: cuda on " + dev.name;
    return c;
  }
  if (requested == BackendKind::Cuda)
    throw InputError("", "--backend", "cuda was requested but no usable GPU: " + dev.error);
  c.kind = BackendKind::Cpu;
  c.note = "backend: no usable GPU (" + dev.error + "), falling back to the CPU";
  return c;
}

}  // namespace inc
