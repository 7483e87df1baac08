// Names of the backend kinds and precisions, and parsing them from text.
#include "model/backend.h"

#include "model/input_error.h"

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

}  // namespace inc
