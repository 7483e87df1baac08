// Errors for bad user input (scenes, meshes, parameters): they name the file, the key path and the reason.
#pragma once

#include <stdexcept>
#include <string>

namespace inc {

class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string key, std::string reason)
      : std::runtime_error(format(file, key, reason)),
        file_(std::move(file)),
        key_(std::move(key)),
        reason_(std::move(reason)) {}
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }
  const std::string& reason() const { return reason_; }

 private:
  static std::string format(const std::string& file, const std::string& key, const std::string& reason) {
    std::string s = file.empty() ? std::string("<input>") : file;
    if (!key.empty()) s += ": " + key;
    return s + ": " + reason;
  }
  std::string file_, key_, reason_;
};

// Exit code for rejected input, as documented in the README and docs/scene-format.md.
constexpr int kExitBadInput = 2;
// Exit code for a simulation stopped by the numerical guard (NaN or energy blow-up).
constexpr int kExitSimulationFailed = 3;

}  // namespace inc
