// A fresh temporary folder per test, removed when the test is done: concurrent runs never share a path.
#pragma once

#include <stdlib.h>  // mkdtemp (POSIX)

#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>

namespace inc::test {

// Created empty under the system's temporary folder as incision_<prefix>_XXXXXX (mkdtemp picks a name no other
// process holds), removed with its contents on destruction. A fixed name let two runs of the suite (ctest -j, two
// worktrees) write into and delete each other's outputs.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix) {
    std::string pattern = (std::filesystem::temp_directory_path() / ("incision_" + prefix + "_XXXXXX")).string();
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("cannot create a temporary folder like " + pattern);
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;  // best effort: a leftover folder must not fail the test
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string str() const { return path_.string(); }
  // A path inside the folder (nothing is created).
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

}  // namespace inc::test
