// Which backend runs a step (CUDA or the CPU fallback) and in what precision: the kinds, their names, parsing.
#pragma once

#include <string>

namespace inc {

enum class BackendKind { Auto, Cuda, Cpu };
enum class Precision { Float32, Float64 };

// "auto" | "cuda" | "cpu"; throws InputError naming `key` otherwise.
BackendKind parseBackend(const std::string& text, const std::string& file = "", const std::string& key = "--backend");
const char* backendName(BackendKind k);
const char* precisionName(Precision p);

}  // namespace inc
