// Tests for the scene key table: it names exactly the keys docs/scene-format.md documents, every row is bound to
// its field, and the loader and writer, which walk the table, read back every key they write.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/scene/embedded_scenes.h"
#include "host/scene/scene_fields.h"
#include "host/scene/scene_json.h"
#include "host/scene/scene_keys.h"
#include "host/scene/scene_loader.h"
#include "model/input_error.h"
#include "test_paths.h"
#include "tests/support/repo_paths.h"

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
      for (const std::string& key : backtickedWords(first_cell))
        keys.push_back(section.empty() ? key : section + "." + key);
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
      << "in host/scene/scene_keys.cpp but in no key table of docs/scene-format.md:"
      << joined(missingFrom(table, documented));
  EXPECT_TRUE(missingFrom(documented, table).empty())
      << "documented in docs/scene-format.md but not in host/scene/scene_keys.cpp:"
      << joined(missingFrom(documented, table));
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
  EXPECT_EQ(sceneKeysUnder("material"), (std::vector<std::string>{"youngs_modulus_pa", "poisson_ratio", "density_kg_m3",
                                                                  "damping_per_s", "cutting"}));
  EXPECT_EQ(sceneKeysUnder("colliders[]", "plane"),
            (std::vector<std::string>{"kind", "point_m", "normal", "friction"}));
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
      const bool device_key_in_place =
          path.rfind("haptics.", 0) == 0 &&
          std::find(table.begin(), table.end(), "haptics.devices[]." + path.substr(8)) != table.end();
      EXPECT_TRUE(device_key_in_place || std::find(table.begin(), table.end(), path) != table.end())
          << "sceneToJson writes " << path << ", which the key table does not have";
    }
  }
}

// ---------------------------------------------------------------------------------------------------------
// The bindings: every row is bound to a field of the struct of its parent object, and every key the table reads
// is written and read back.

namespace {

const SceneKey& keyAt(const std::string& path) {
  for (const SceneKey& k : sceneKeys())
    if (path == k.path) return k;
  throw std::logic_error("no row " + path);
}

// "tools[].path[].t_s" -> "tools[].path[]" and "t_s"; "name" -> "" and "name".
std::string parentOf(const std::string& path) {
  const std::size_t dot = path.rfind('.');
  return dot == std::string::npos ? "" : path.substr(0, dot);
}
std::string nameOf(const std::string& path) { return path.substr(path.rfind('.') + 1); }
// The row of the object or array a parent path names: "tools[].path[]" -> "tools[].path".
std::string rowOf(const std::string& parent) {
  const bool element = parent.size() > 2 && parent.compare(parent.size() - 2, 2, "[]") == 0;
  return element ? parent.substr(0, parent.size() - 2) : parent;
}

// The struct that holds `path`'s value in `s`, through the bindings (element 0 of each array on the way); nullptr
// when an array on the way is empty.
const void* ownerIn(const Scene& s, const std::string& path) {
  const std::string parent = parentOf(path);
  if (parent.empty()) return &s;
  const std::string row = rowOf(parent);
  const SceneField& f = *keyAt(row).field;
  const void* o = f.of_scene ? &s : ownerIn(s, row);
  if (!o || (f.shape == SceneField::Shape::kArray && f.count(o) == 0)) return nullptr;
  return f.child(o, 0);
}

nlohmann::ordered_json valueOf(const SceneField& f, const void* owner) {
  SceneJson j;
  f.write(owner, "v", j);
  return j["v"];
}
nlohmann::ordered_json defaultOf(const SceneField& f) {
  SceneJson j;
  f.write_default("v", j);
  return j["v"];
}

// Whether the key applies to `owner`'s kind (a row with `kinds` under an object with a `kind`).
bool usedByOwner(const SceneKey& k, const void* owner) {
  if (k.kinds[0] == '\0') return true;
  const std::string parent = parentOf(k.path);
  const SceneKey& kind = keyAt(parent.empty() ? "kind" : parent + ".kind");
  return sceneKeyUsedBy(k, kind.field->text(owner));
}

// Every key of a and b equal, through the table (values, the writer's conditions, array sizes and forms).
void expectSameKeys(const std::string& rows, const void* a, const void* b, const Scene& sa, const Scene& sb) {
  for (const SceneRow& row : sceneRowsUnder(rows)) {
    const SceneField& f = *row.key->field;
    const std::string path = scene_json::joinPath(rows, row.name);
    const void* oa = f.of_scene ? &sa : a;
    const void* ob = f.of_scene ? &sb : b;
    EXPECT_EQ(f.writtenFor(oa), f.writtenFor(ob)) << path;
    switch (f.shape) {
      case SceneField::Shape::kValue: EXPECT_EQ(valueOf(f, oa), valueOf(f, ob)) << path; break;
      case SceneField::Shape::kObject: expectSameKeys(path, f.child(oa, 0), f.child(ob, 0), sa, sb); break;
      case SceneField::Shape::kArray:
        EXPECT_EQ(f.asSingle(oa), f.asSingle(ob)) << path;
        ASSERT_EQ(f.count(oa), f.count(ob)) << path;
        for (std::size_t i = 0; i < f.count(oa); ++i)
          expectSameKeys(path + "[]", f.child(oa, i), f.child(ob, i), sa, sb);
        break;
    }
  }
}
void expectSameKeys(const Scene& a, const Scene& b) { expectSameKeys("", &a, &b, a, b); }

// Values other than `cur` of the field's type, most of them inside its rule.
std::vector<nlohmann::ordered_json> otherValues(const SceneField& f, const nlohmann::ordered_json& cur) {
  using J = nlohmann::ordered_json;
  std::vector<J> out;
  const FieldRule& rule = f.rule;
  const std::string type = f.type;
  if (type == "boolean") {
    out.push_back(!cur.get<bool>());
  } else if (type == "string") {
    if (rule.kind == FieldRule::Kind::kChoice) {
      for (const std::string& c : rule.choices) out.push_back(c);
    } else {
      out.push_back(cur.get<std::string>() + "x");
    }
  } else if (type == "integer") {
    const long long v = cur.get<long long>();
    for (long long c : {v + 1, v - 1})
      if (rule.accepts(double(c))) out.push_back(c);
  } else if (type == "number") {
    const double v = cur.get<double>();
    std::vector<double> c = {v * 0.9, v * 1.1, v + 0.25};
    if (rule.kind == FieldRule::Kind::kInterval) c.push_back(0.5 * (rule.lo + rule.hi));
    for (double x : c)
      if (rule.accepts(x)) out.push_back(x);
  } else if (type == "vec3") {
    if (rule.kind == FieldRule::Kind::kUnit) {
      out = {J::array({0.0, 0.6, 0.8}), J::array({0.6, 0.0, 0.8}), J::array({0.8, 0.6, 0.0})};
    } else {
      const double x = cur[0].get<double>(), y = cur[1].get<double>(), z = cur[2].get<double>();
      out = {J::array({x * 0.9, y * 0.9, z * 0.9}), J::array({x + 0.001, y + 0.002, z + 0.003}),
             J::array({x - 0.001, y - 0.002, z - 0.003})};
    }
  }
  return out;
}

// Sets the key at `k` in (a copy of) `base` to `next` through its binding, writes the scene, reads it back and
// checks the value came back (and the writer is a fixed point), and that setting it changed no other key of its
// object (two rows bound to one field). "" when all holds, else what went wrong.
std::string writtenAndReadBack(const Scene& base, const std::string& base_dir, const SceneKey& k,
                               const nlohmann::ordered_json& next) {
  Scene s = base;
  const SceneField& f = *k.field;
  const std::string key = nameOf(k.path);
  void* owner = const_cast<void*>(ownerIn(s, k.path));
  std::vector<std::pair<const SceneField*, nlohmann::ordered_json>> others;
  for (const SceneRow& row : sceneRowsUnder(parentOf(k.path))) {
    const SceneField& o = *row.key->field;
    if (row.key != &k && o.shape == SceneField::Shape::kValue && !o.of_scene && *o.owner == *f.owner)
      others.push_back({&o, valueOf(o, owner)});
  }
  try {
    const nlohmann::json obj = {{key, nlohmann::json::parse(next.dump())}};
    f.read(scene_json::ObjectReader(obj, "test", ""), key, owner);
  } catch (const InputError& e) {
    return std::string("refused: ") + e.what();
  }
  if (valueOf(f, owner) != next) return "set as " + valueOf(f, owner).dump();
  for (const auto& [o, before] : others)
    if (valueOf(*o, owner) != before) return "setting it changed another key of its object";
  if (!f.writtenFor(owner)) return "not written in this scene";
  const std::string text = sceneToJson(s);
  Scene back;
  try {
    back = parseScene(text, s.file, base_dir);
  } catch (const InputError& e) {
    return std::string("written scene refused: ") + e.what();
  }
  const void* owner_back = ownerIn(back, k.path);
  if (!owner_back) return "its object is gone after the round trip";
  if (valueOf(f, owner_back) != next) return "read back as " + valueOf(f, owner_back).dump();
  if (sceneToJson(back) != text) return "the writer is not a fixed point";
  return "";
}

struct BaseScene {
  Scene scene;
  std::string dir;
};

// Scenes that between them hold every object the table describes (the walk looks at the first element of each
// array): each geometry kind, tools, a plane collider and a box collider first in their lists,
// fixed boxes, tearing regions, one device in `haptics` itself, and (haptic_two_hands) the device list and the BEM
// global model with its surface point.
std::vector<BaseScene> baseScenes() {
  const std::string mesh = inc::test::sourcePath("scenes/haptic_two_hands_bem.obj");
  const std::string texts[] = {
      R"({"geometry": {"kind": "box", "size_m": [0.06, 0.04, 0.03], "spacing_m": 0.01},
          "models": {"mls": true, "pbd_metaballs": true, "cutting": true, "haptics": true},
          "fixed": [{"min_m": [-1, -1, -1], "max_m": [1, 1, -0.01]}],
          "tools": [{"name": "t", "path": [{"t_s": 0, "position_m": [0, 0, 0.05]}]}],
          "colliders": [{"kind": "plane", "point_m": [0, 0, -0.05], "normal": [0, 0, 1]},
                        {"kind": "box", "min_m": [-0.2, -0.2, -0.2], "max_m": [0.2, 0.2, -0.1]}],
          "haptics": {"device": "udp", "surface_point_m": [0, 0, 0.015]}})",
      R"({"geometry": {"kind": "sphere", "radius_m": 0.03, "spacing_m": 0.01}, "models": {"mls": true},
          "colliders": [{"kind": "box", "min_m": [-0.2, -0.2, -0.2], "max_m": [0.2, 0.2, -0.1]}]})",
      R"({"geometry": {"kind": "ellipsoid", "radii_m": [0.05, 0.04, 0.03], "spacing_m": 0.01},
          "models": {"pbd_metaballs": true}})",
      R"({"geometry": {"kind": "mesh", "mesh": ")" + mesh + R"(", "spacing_m": 0.01}, "models": {"mls": true}})",
      R"({"geometry": {"kind": "box", "size_m": [0.1, 0.1, 0.01], "spacing_m": 0.005}, "models": {"tearing": true},
          "tearing": {"regions": [{"min_m": [0, 0, 0], "max_m": [1, 1, 1], "k_pa": 100, "tau_f_pa": 5}]}})",
  };
  std::vector<BaseScene> out;
  for (const std::string& t : texts) out.push_back({parseScene(t, "scenes/base.json", "."), "."});
  const std::string two_hands = inc::test::sourcePath("scenes/haptic_two_hands.json");
  out.push_back({loadSceneFile(two_hands), fs::path(two_hands).parent_path().string()});
  return out;
}

}  // namespace

TEST(SceneKeys, EveryRowIsBoundToAFieldOfItsParentsStruct) {
  std::vector<std::string> by_code;
  for (const SceneKey& k : sceneKeys()) {
    SCOPED_TRACE(k.path);
    ASSERT_TRUE(k.field) << k.path << " has no binding";
    const SceneField& f = *k.field;
    // The binding's type is the documented one ("array of objects" is an array).
    EXPECT_EQ(std::string(k.type).rfind(f.type, 0), 0u) << "documented as " << k.type << ", bound as " << f.type;
    const std::string parent = parentOf(k.path);
    const std::type_info& expected =
        f.of_scene || parent.empty() ? typeid(Scene) : *keyAt(rowOf(parent)).field->element;
    EXPECT_TRUE(*f.owner == expected) << "binds a field of " << f.owner->name() << ", expected " << expected.name();
    if (f.shape == SceneField::Shape::kValue) {
      EXPECT_TRUE(f.read && f.write && f.text && f.write_default);
      if (f.read_by_code) {
        EXPECT_GT(std::string(f.read_by_code).size(), 20u) << "say why its section's reader reads it";
        by_code.push_back(k.path);
      }
    } else {
      EXPECT_TRUE(f.element && f.child) << "an object or array needs its child struct";
      EXPECT_EQ(f.shape == SceneField::Shape::kArray, bool(f.count));
      EXPECT_EQ(f.read_by_code, nullptr);
    }
  }
  // The keys the table writes but code reads: each resolves a path or loads a file. A new one belongs here only
  // with a reason of that kind; every other key is read by the table.
  EXPECT_EQ(by_code, (std::vector<std::string>{"geometry.mesh", "haptics.global_mesh", "haptics.global_cache",
                                               "haptics.devices[].trajectory"}));
}

// A binding's range rule is the documented range: "> 0" (or "(0, ..."), ">= 0" (or "[0, ..."), the interval as
// written, each component > 0, a unit vector, every choice named.
TEST(SceneKeys, BindingRulesAreTheDocumentedRanges) {
  int rules = 0;
  for (const SceneKey& k : sceneKeys()) {
    const FieldRule& r = k.field->rule;
    if (r.kind == FieldRule::Kind::kNone) continue;
    ++rules;
    const std::string range = k.range, bound = formatNumber(r.lo);
    auto starts = [&](const std::string& p) { return range.rfind(p, 0) == 0; };
    switch (r.kind) {
      case FieldRule::Kind::kAbove: EXPECT_TRUE(starts("> " + bound) || starts("(" + bound + ",")) << k.path; break;
      case FieldRule::Kind::kAtLeast: EXPECT_TRUE(starts(">= " + bound) || starts("[" + bound + ",")) << k.path; break;
      case FieldRule::Kind::kChoice:
        for (const std::string& c : r.choices) EXPECT_NE(range.find(c), std::string::npos) << k.path << ": " << c;
        break;
      default: EXPECT_TRUE(starts(r.text())) << k.path << ": the binding checks " << r.text(); break;
    }
    if (k.field->type == std::string("integer") && r.kind == FieldRule::Kind::kInterval) {
      EXPECT_TRUE(r.interval.front() == '[' && r.interval.back() == ']') << k.path << ": an integer range is closed";
    }
  }
  EXPECT_GT(rules, 70);  // about 90 of the keys have a simple rule
}

// Each key the table reads, set away from its default through its binding in a scene that writes it, is written
// by sceneToJson and read back by parseScene to the same value.
TEST(SceneKeys, EveryTableReadKeyIsWrittenAndReadBack) {
  const std::vector<BaseScene> bases = baseScenes();
  int keys = 0;
  for (const SceneKey& k : sceneKeys()) {
    const SceneField& f = *k.field;
    if (f.shape != SceneField::Shape::kValue || f.read_by_code) continue;
    ++keys;
    const nlohmann::ordered_json fallback = defaultOf(f);
    std::vector<std::string> tried;
    bool done = false;
    for (const BaseScene& b : bases) {
      const void* owner = ownerIn(b.scene, k.path);
      if (!owner || !usedByOwner(k, owner)) continue;
      const nlohmann::ordered_json cur = valueOf(f, owner);
      // Values other than the current one first (the write must carry the change), then the base's own value.
      std::vector<nlohmann::ordered_json> values = otherValues(f, cur);
      values.push_back(cur);
      for (const nlohmann::ordered_json& next : values) {
        if (next == fallback || (&next != &values.back() && next == cur)) continue;
        const std::string why = writtenAndReadBack(b.scene, b.dir, k, next);
        if (why.empty()) {
          done = true;
          break;
        }
        tried.push_back(next.dump() + " in " + b.scene.file + ": " + why);
      }
      if (done) break;
    }
    std::string all;
    for (const std::string& t : tried) all += "\n  " + t;
    EXPECT_TRUE(done) << k.path << " was not written and read back with a value other than its default" << all;
  }
  EXPECT_GT(keys, 100);
}

// A Scene with every field at its default (one model on, as the loader demands) writes and reads back unchanged.
TEST(SceneKeys, DefaultSceneRoundTrips) {
  Scene a;
  a.models.mls = true;
  const std::string text = sceneToJson(a);
  const Scene b = parseScene(text, "scenes/default.json", ".");
  expectSameKeys(a, b);
  EXPECT_EQ(sceneToJson(b), text);
}

// Every shipped and embedded scene: load(write(s)) == s, and writing again gives the same text.
TEST(SceneKeys, ShippedScenesRoundTrip) {
  std::vector<std::pair<Scene, std::string>> scenes;
  for (const auto& e : fs::directory_iterator(inc::test::sourcePath("scenes")))
    if (e.path().extension() == ".json") scenes.push_back({loadSceneFile(e.path().string()), e.path().parent_path()});
  for (const EmbeddedScene& e : embeddedScenes())
    scenes.push_back({parseScene(e.json, std::string("<embedded:") + e.name + ">", ""), ""});
  ASSERT_GE(scenes.size(), 10u);
  for (const auto& [a, dir] : scenes) {
    SCOPED_TRACE(a.file);
    const std::string text = sceneToJson(a);
    const Scene b = parseScene(text, a.file, dir);
    expectSameKeys(a, b);
    EXPECT_EQ(sceneToJson(b), text);
  }
}
