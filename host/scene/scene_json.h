// Checked reading of JSON scene text: parse errors with line, column and key path; typed getters naming the key.
#pragma once

#include "base/format_number.h"

#include <cstddef>
#include <initializer_list>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "physics/vec3.h"

namespace inc {
namespace scene_json {

struct TextPosition {
  std::size_t line = 1;    // 1-based
  std::size_t column = 1;  // 1-based, in bytes
};

// Line and column of the byte at 0-based `offset` (clamped to the end of the text).
TextPosition positionOfByte(const std::string& text, std::size_t offset);

// Levenshtein distance (insertions, deletions, substitutions), for did-you-mean.
std::size_t editDistance(const std::string& a, const std::string& b);

// The known key closest to `key` when it is close enough to be a likely typo, else "".
std::string closestKey(const std::string& key, const std::vector<std::string>& known);

// How deep objects and arrays may nest in a scene file (a scene needs about five levels).
inline constexpr std::size_t kMaxSceneJsonDepth = 64;

// Parses `text`; throws InputError(file, key path at the failure, reason) for invalid JSON (with line and
// column), numbers that overflow a double, keys repeated within one object, and nesting deeper than
// kMaxSceneJsonDepth (checked while reading, before any recursive walk of the document).
nlohmann::json parseChecked(const std::string& text, const std::string& file);

// Short rendering of a JSON value for messages ("a string (\"abc\")", "a number (3.5)").
std::string describeValue(const nlohmann::json& v);

using ::inc::formatNumber;  // base/format_number.h

// A view of one JSON object at a key path; every getter names file and key path in its errors.
class ObjectReader {
 public:
  // Throws when `obj` is not an object ("expected an object, got ...").
  ObjectReader(const nlohmann::json& obj, std::string file, std::string path);

  // Rejects any key not in `known` (did-you-mean by edit distance, else the list of known keys).
  void allowOnly(const std::vector<std::string>& known) const;

  bool has(const std::string& key) const { return obj_->contains(key); }
  std::string keyPath(const std::string& key) const;
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  const nlohmann::json& value() const { return *obj_; }

  // Typed getters: `fallback` when the key is absent; InputError on a wrong type or a non-finite number.
  double number(const std::string& key, double fallback) const;
  long long integer(const std::string& key, long long fallback) const;
  bool boolean(const std::string& key, bool fallback) const;
  std::string string(const std::string& key, const std::string& fallback) const;
  // One of `choices` (did-you-mean on a near miss).
  std::string choice(const std::string& key, const std::string& fallback,
                     const std::vector<std::string>& choices) const;
  Vec3d vec3(const std::string& key, const Vec3d& fallback) const;
  // The object at `key`; throws when absent ("is required") or not an object.
  ObjectReader object(const std::string& key) const;
  // The array at `key`, or nullptr when absent; throws when not an array.
  const nlohmann::json* array(const std::string& key) const;

  [[noreturn]] void fail(const std::string& key, const std::string& reason) const;

 private:
  const nlohmann::json* obj_;
  std::string file_, path_;
};

// Joins key paths: join("tools[0]", "path") == "tools[0].path"; join("", "name") == "name".
std::string joinPath(const std::string& parent, const std::string& key);
std::string indexPath(const std::string& parent, std::size_t index);

// A file path a scene names: relative paths are taken from base_dir (the scene file's folder; "" = the current
// folder); the result is absolute and normalised.
std::string resolvePath(const std::string& path, const std::string& base_dir);

// Reads a finite number / integer / 3-vector from a JSON value at `path` (for array elements).
double numberAt(const nlohmann::json& v, const std::string& file, const std::string& path);
Vec3d vec3At(const nlohmann::json& v, const std::string& file, const std::string& path);

}  // namespace scene_json
}  // namespace inc
