// The shared open meshes (../shared/organs/SOURCES.md: "must be refused clearly") are refused when a scene is read.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "host/scene/scene_loader.h"
#include "model/input_error.h"
#include "tests/support/repo_paths.h"

namespace inc {
namespace {

// The shared open meshes (SOURCES.md: "must be refused clearly") are refused at load under geometry.mesh, naming
// the mesh file and what is wrong.
TEST(SharedOpenMeshes, AreRefusedNamingTheKeyAndTheDefect) {
  for (const char* name : {"frog_body.obj", "c_open.obj"}) {
    const std::string path = test::sharedPath(std::string("organs/") + name);
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent (shared organ meshes are not committed)";
    const std::string scene = R"({"geometry": {"kind": "mesh", "mesh": ")" + path +
                              R"(", "mesh_scale": 0.01}, "models": {"pbd_metaballs": true}})";
    try {
      parseScene(scene, "user.json", ".");
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), "geometry.mesh") << e.what();
      EXPECT_NE(e.reason().find(name), std::string::npos) << e.what();
      EXPECT_NE(e.reason().find("closed, manifold, consistently oriented surface is needed"), std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace inc
