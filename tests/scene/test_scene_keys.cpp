// Tests for the scene key table: it names exactly the keys docs/scene-format.md documents, and the loader and
// writer use no other.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/scene/scene_keys.h"
#include "host/scene/scene_loader.h"
#include "model/input_error.h"
#include "test_paths.h"

using namespace inc;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> backtickedWords(const std::string& text) {
  std::vector<std::string> out;
  static const std::regex word("`([^`]+)`");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), word); it != std::sregex_iterator(); ++it)
    out.push_back((*it)[1].str());
  return out;
}

// "tools[i].path[k]" -> "tools[].path[]": the table's spelling of "any element".
std::string anyElement(const std::string& path) { return std::regex_replace(path, std::regex(R"(\[[a-z]\])"), "[]"); }

// The section a heading names: "### `fixed` (array)" -> "fixed[]", "### Top level" -> "".
std::string headingSection(const std::string& heading) {
  const std::vector<std::string> words = backtickedWords(heading);
  if (words.empty()) return "";
  return words.front() + (heading.find("(array") != std::string::npos ? "[]" : "");
}

bool endsWithColon(const std::string& line) {
  const std::size_t last = line.find_last_not_of(" \t");
  return last != std::string::npos && line[last] == ':';
}

// Every key path docs/scene-format.md's key tables name. A key table is one whose header starts with "| key |", in a
// "### " section; its keys sit under the section the heading names, or, when the line just above the table is a
// label ending in ':' ("Keyframe (`tools[i].path[k]`):"), under the first path that label quotes.
std::vector<std::string> documentedKeys(const fs::path& doc) {
  std::ifstream in(doc);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::vector<std::string> keys;
  std::string heading;
  bool in_section = false;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string& l = lines[i];
    if (l.rfind("## ", 0) == 0) in_section = false;
    if (l.rfind("### ", 0) == 0) {
      heading = l;
      in_section = true;
    }
    if (!in_section || l.rfind("| key |", 0) != 0) continue;
    std::size_t above = i;
    while (above > 0 && lines[above - 1].find_first_not_of(" \t") == std::string::npos) --above;
    const std::string label = above > 0 ? lines[above - 1] : "";
    std::string section = headingSection(heading);
    if (label.rfind("### ", 0) != 0 && endsWithColon(label) && !backtickedWords(label).empty())
      section = anyElement(backtickedWords(label).front());
    std::size_t row = i + 2;  // past the header and its |---| line
    for (; row < lines.size() && lines[row].rfind("|", 0) == 0; ++row) {
      const std::string first_cell = lines[row].substr(1, lines[row].find('|', 1) - 1);
      for (const std::string& key : backtickedWords(first_cell)) keys.push_back(section.empty() ? key : section + "." + key);
    }
    i = row;
  }
  return keys;
}

std::vector<std::string> tableKeys() {
  std::vector<std::string> out;
  for (const SceneKey& k : sceneKeys()) out.push_back(k.path);
  return out;
}

std::vector<std::string> missingFrom(const std::vector<std::string>& from, const std::vector<std::string>& in) {
  std::vector<std::string> out;
  for (const std::string& k : from)
    if (std::find(in.begin(), in.end(), k) == in.end()) out.push_back(k);
  return out;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& k : v) s += "\n  " + k;
  return s;
}

// Every key path a JSON document holds, array elements spelt "[]".
void collectPaths(const nlohmann::ordered_json& j, const std::string& path, std::set<std::string>& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      const std::string child = path.empty() ? it.key() : path + "." + it.key();
      out.insert(child);
      collectPaths(it.value(), child, out);
    }
  } else if (j.is_array()) {
    for (const auto& e : j) collectPaths(e, path + "[]", out);
  }
}

}  // namespace

TEST(SceneKeys, TableAndDocsNameTheSameKeys) {
  const fs::path doc = fs::path(INCISION_SOURCE_DIR) / "docs" / "scene-format.md";
  ASSERT_TRUE(fs::exists(doc)) << doc;
  const std::vector<std::string> documented = documentedKeys(doc);
  const std::vector<std::string> table = tableKeys();
  ASSERT_GT(documented.size(), 100u);  // the parse found the tables (about 130 keys)
  EXPECT_TRUE(missingFrom(table, documented).empty())
      << "in host/scene/scene_keys.cpp but in no key table of docs/scene-format.md:" << joined(missingFrom(table, documented));
  EXPECT_TRUE(missingFrom(documented, table).empty())
      << "documented in docs/scene-format.md but not in host/scene/scene_keys.cpp:" << joined(missingFrom(documented, table));
}

TEST(SceneKeys, EachKeyOnceWithItsParentAndADescription) {
  std::set<std::string> seen;
  for (const SceneKey& k : sceneKeys()) {
    const std::string path = k.path;
    EXPECT_TRUE(seen.insert(path).second) << path << " is in the table twice";
    EXPECT_FALSE(std::string(k.type).empty()) << path;
    EXPECT_FALSE(std::string(k.unit).empty()) << path;
    EXPECT_FALSE(std::string(k.range).empty()) << path;
    EXPECT_FALSE(std::string(k.fallback).empty()) << path;
    // A nested key's parent comes first: "tools[].path[].t_s" needs "tools[].path", "material.cutting.x" needs
    // "material.cutting".
    const std::size_t dot = path.rfind('.');
    if (dot == std::string::npos) continue;
    std::string parent = path.substr(0, dot);
    if (parent.size() > 2 && parent.compare(parent.size() - 2, 2, "[]") == 0) parent.resize(parent.size() - 2);
    EXPECT_TRUE(seen.count(parent)) << path << " comes before (or without) its parent " << parent;
  }
}

TEST(SceneKeys, ChildrenInReaderOrder) {
  EXPECT_EQ(sceneKeysUnder("material"),
            (std::vector<std::string>{"youngs_modulus_pa", "poisson_ratio", "density_kg_m3", "damping_per_s", "cutting"}));
  EXPECT_EQ(sceneKeysUnder("colliders[]", "plane"), (std::vector<std::string>{"kind", "point_m", "normal", "friction"}));
  EXPECT_EQ(sceneKeysUnder("colliders[]", "box"), (std::vector<std::string>{"kind", "min_m", "max_m", "friction"}));
  EXPECT_EQ(sceneKeysUnder("tools[].path[]"), (std::vector<std::string>{"t_s", "position_m", "direction"}));
  EXPECT_EQ(kindSpecificKeysUnder("geometry", "sphere"), (std::vector<std::string>{"center_m", "radius_m"}));
  EXPECT_EQ(sceneKeysUnder("").front(), "name");
  EXPECT_TRUE(sceneKeysUnder("no_such_section").empty());
}

// The writer writes only keys the table (and so the docs) know: a scene with every array filled in, both haptics forms.
TEST(SceneKeys, WriterUsesOnlyTableKeys) {
  const char* scenes[] = {
      R"({"geometry": {"kind": "box", "size_m": [0.1, 0.04, 0.04], "spacing_m": 0.01},
          "models": {"pbd_metaballs": true, "cutting": true, "haptics": true},
          "fixed": [{"min_m": [-0.06, -0.03, -0.03], "max_m": [-0.04, 0.03, 0.03]}],
          "tools": [{"name": "s", "kind": "scalpel", "path": [{"t_s": 0, "position_m": [0, 0, 0.05]}]}],
          "colliders": [{"kind": "plane", "point_m": [0, 0, -0.05], "normal": [0, 0, 1]},
                        {"kind": "box", "min_m": [-0.2, -0.2, -0.2], "max_m": [0.2, 0.2, -0.1]}],
          "haptics": {"devices": [{"name": "left", "device": "udp", "udp_port": 47000},
                                  {"name": "right", "device": "udp", "udp_port": 47001}]}})",
      R"({"geometry": {"kind": "box"}, "models": {"tearing": true},
          "tearing": {"regions": [{"min_m": [0, 0, 0], "max_m": [1, 1, 1], "k_pa": 100}]}})",
      R"({"geometry": {"kind": "sphere"}, "models": {"mls": true, "haptics": true}, "haptics": {"device": "udp"}})",
  };
  const std::vector<std::string> table = tableKeys();
  for (const char* text : scenes) {
    const Scene s = parseScene(text, "scenes/keys.json", ".");
    std::set<std::string> written;
    collectPaths(nlohmann::ordered_json::parse(sceneToJson(s)), "", written);
    for (const std::string& path : written) {
      // The one-device form writes a device's keys in `haptics` itself (the table lists them under devices[]).
      const bool device_key_in_place = path.rfind("haptics.", 0) == 0 &&
                                       std::find(table.begin(), table.end(), "haptics.devices[]." + path.substr(8)) !=
                                           table.end();
      EXPECT_TRUE(device_key_in_place || std::find(table.begin(), table.end(), path) != table.end())
          << "sceneToJson writes " << path << ", which the key table does not have";
    }
  }
}
