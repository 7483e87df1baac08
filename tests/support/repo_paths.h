// Where the tests find the repository's files at run time: the source tree (scenes/) and the shared organ meshes.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

#include "test_paths.h"

namespace inc::test {

namespace detail {

// The first of the running binary's folder and its ancestors that holds scenes/: the tree the binary was built
// in, wherever that tree now lies (a copy on another machine, a moved checkout). Empty when there is none.
inline std::string treeOfRunningBinary() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  for (std::filesystem::path dir = exe.parent_path(); !dir.empty(); dir = dir.parent_path()) {
    if (std::filesystem::is_directory(dir / "scenes", ec)) return dir.string();
    if (dir == dir.root_path()) break;
  }
  return {};
}

}  // namespace detail

// The source tree: $INCISION_SOURCE_DIR when set, else the running binary's tree when it holds scenes/, else the
// path configured at build time (INCISION_SOURCE_DIR of test_paths.h, which goes stale once the binaries run from
// another copy of the tree).
inline const std::string& sourceDir() {
  static const std::string dir = [] {
    if (const char* env = std::getenv("INCISION_SOURCE_DIR"); env && *env) return std::string(env);
    const std::string tree = detail::treeOfRunningBinary();
    return tree.empty() ? std::string(INCISION_SOURCE_DIR) : tree;
  }();
  return dir;
}

// A file of the source tree, e.g. sourcePath("scenes/liver_grasp.json").
inline std::string sourcePath(const std::string& relative) { return sourceDir() + "/" + relative; }

// The shared organ meshes and papers, kept beside the checkout: $INCISION_SHARED_DIR when set, else shared/ inside
// the source tree when there is one (a copied tree carries it there), else the source tree's ../shared.
inline const std::string& sharedDir() {
  static const std::string dir = [] {
    if (const char* env = std::getenv("INCISION_SHARED_DIR"); env && *env) return std::string(env);
    std::error_code ec;
    const std::filesystem::path inside = std::filesystem::path(sourceDir()) / "shared";
    return std::filesystem::is_directory(inside, ec) ? inside.string() : sourceDir() + "/../shared";
  }();
  return dir;
}

// A file of the shared folder, e.g. sharedPath("organs/liver-smooth.obj").
inline std::string sharedPath(const std::string& relative) { return sharedDir() + "/" + relative; }

}  // namespace inc::test
