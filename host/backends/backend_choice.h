// Resolving the requested backend against what this build and this machine can run.
#pragma once

#include <cstddef>
#include <string>

#include "model/backend.h"

namespace inc {

struct BackendChoice {
  BackendKind kind = BackendKind::Cpu;  // never Auto once resolved
  std::string note;                     // one line for the user (fallback reason, device name)
  std::size_t device_memory_bytes = 0;  // Cuda: the device's global memory (the memory check's budget); else 0
};

// Auto -> CUDA when compiled in and a device is usable, else CPU with a one-line note.
// Cuda without a usable device throws InputError with the reason (never crashes).
BackendChoice resolveBackend(BackendKind requested);

}  // namespace inc
