// Resolving the requested backend against what this build and this machine can run.
#pragma once

#include <string>

#include "model/backend.h"

namespace inc {

struct BackendChoice {
  BackendKind kind = BackendKind::Cpu;  // never Auto once resolved
  std::string note;                     // one line for the user (fallback reason, device name)
};

// Auto -> CUDA when compiled in and a device is usable, else CPU with a one-line note.
// Cuda without a usable device throws InputError with the reason (never crashes).
BackendChoice resolveBackend(BackendKind requested);

}  // namespace inc
