// Scenes compiled into the binary, so `incision run` works on a fresh machine with no files at all.
#pragma once

#include <string>
#include <vector>

namespace inc {

struct EmbeddedScene {
  const char* name;
  const char* summary;
  const char* json;
};

const std::vector<EmbeddedScene>& embeddedScenes();
// The scene the README's first command runs.
const EmbeddedScene& defaultEmbeddedScene();
// nullptr when no embedded scene has that name.
const EmbeddedScene* findEmbeddedScene(const std::string& name);

}  // namespace inc
