// Backend selection: the host asks for a step; this decides whether CUDA or the CPU fallback runs it.
#pragma once

#include <string>

namespace inc {

enum class BackendKind { Auto, Cuda, Cpu };
enum class Precision { Float32, Float64 };

struct BackendChoice {
  BackendKind kind = BackendKind::Cpu;  // never Auto once resolved
  std::string note;                     // one line for the user (fallback reason, device name)
};

// "auto" | "cuda" | "cpu"; throws InputError naming `key` otherwise.
BackendKind parseBackend(const std::string& text, const std::string& file = "", const std::string& key = "--backend");
const char* backendName(BackendKind k);
const char* precisionName(Precision p);

// Auto -> CUDA when compiled in and a device is usable, else CPU with a one-line note.
// Cuda without a usable device throws InputError with the reason (never crashes).
BackendChoice resolveBackend(BackendKind requested);

}  // namespace inc
