// Resolves --backend auto|cuda|cpu against what this build and this machine can run.
#include "host/backends/backend_choice.h"

#include "kernels/device_info.h"
#include "model/input_error.h"

namespace inc {

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
    c.device_memory_bytes = dev.global_memory_bytes;
    return c;
  }
  if (requested == BackendKind::Cuda)
    throw InputError("", "--backend", "cuda was requested but no usable GPU: " + dev.error);
  c.kind = BackendKind::Cpu;
  c.note = "backend: no usable GPU (" + dev.error + "), falling back to the CPU";
  return c;
}

}  // namespace inc
