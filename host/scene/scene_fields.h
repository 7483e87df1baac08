// Bindings of scene keys to the fields of the Scene structs, and the table walks that read and write them.
#pragma once

#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <typeinfo>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "host/scene/scene.h"
#include "host/scene/scene_json.h"
#include "host/scene/scene_keys.h"

namespace inc {

using SceneJson = nlohmann::ordered_json;

// The range a key's binding checks as it reads: the simple rules only (a bound, an interval, each component > 0,
// a unit vector, one of a list). Rules between keys stay in the section readers of scene_loader.cpp.
struct FieldRule {
  enum class Kind { kNone, kAbove, kAtLeast, kInterval, kEachAbove0, kUnit, kChoice };
  Kind kind = Kind::kNone;
  double lo = 0, hi = 0;  // kAbove, kAtLeast: lo; kInterval: both
  bool lo_open = false, hi_open = false;
  std::string interval;  // kInterval: as written, "[0, 0.5)"
  std::string note;      // kAbove, kInterval: message text after the range (" Hz", " (eq. 14 uses 0.5)")
  std::string zero_reason, huge_reason;  // kUnit: the reasons for a zero and for an overflowing vector
  std::vector<std::string> choices;      // kChoice

  bool accepts(double v) const;
  // In the docs' words ("> 0", "[0, 0.5)", "each > 0", "jacobi, gauss_seidel"); "" for kNone.
  std::string text() const;
};

FieldRule above(double lo, std::string note = "");                   // v > lo: "must be > lo<note> (got v)"
FieldRule atLeast(double lo);                                        // v >= lo: "must be >= lo (got v)"
FieldRule interval(const std::string& text, std::string note = "");  // "[0, 1)": "must lie in [0, 1)<note> (got v)"
FieldRule eachAbove0();  // vec3: "every component must be > 0 (component c is x)"
FieldRule unitVector(std::string zero_reason, std::string huge_reason);  // vec3: non-zero, normalised on load

// One row's binding: where its value lives and how it is read, checked and written. Type-erased: `owner` is a
// pointer to the struct of the row's parent object (GeometrySpec for geometry.*, ToolSpec for tools[].*, Scene
// for the top level); the walks below check that it is the struct they hold.
struct SceneField {
  enum class Shape { kValue, kObject, kArray };
  Shape shape = Shape::kValue;
  const char* type = "";                    // number, integer, boolean, string, vec3, object, array
  const std::type_info* owner = nullptr;    // the struct holding the value
  const std::type_info* element = nullptr;  // objects and arrays: the struct of the child (of each element)
  bool of_scene = false;                    // an object the Scene holds rather than its parent's struct
  FieldRule rule;
  const char* required = nullptr;      // absent -> "is required (<required>)"; nullptr: optional
  const char* read_by_code = nullptr;  // nullptr: the walk reads it; else why its section's reader does

  // Values. read: the value of `key` in `r` (the struct's current value when absent), checked by the rule.
  std::function<void(const scene_json::ObjectReader& r, const std::string& key, void* owner)> read;
  std::function<void(const void* owner, const std::string& key, SceneJson& j)> write;
  std::function<std::string(const void* owner)> text;  // a string or choice's value (an object's kind)
  std::function<void(const std::string& key, SceneJson& j)> write_default;  // a default-constructed owner's value
  // The writer's condition (tools[].friction only when non-zero); empty: always written.
  std::function<bool(const void* owner)> written;
  // Objects (index 0) and arrays: the child struct; arrays: the element count.
  std::function<const void*(const void* owner, std::size_t index)> child;
  std::function<std::size_t(const void* owner)> count;
  // Arrays: written as its one element's keys in the parent object (haptics' single-device form); empty: never.
  std::function<bool(const void* owner)> as_single;

  bool writtenFor(const void* o) const { return !written || written(o); }
  bool asSingle(const void* o) const { return as_single && as_single(o); }
};

// What a row's binding factory returns; `.required(...)`, `.when(...)` and `.readByCode(...)` refine it, and the
// row stores it as its SceneKey::field.
template <class Owner>
class FieldDef {
 public:
  explicit FieldDef(std::shared_ptr<SceneField> f) : f_(std::move(f)) {}
  // The key must be given: "is required (<hint>)".
  FieldDef required(const char* hint) && {
    f_->required = hint;
    return std::move(*this);
  }
  // Written only when `pred` holds for its struct.
  FieldDef when(bool (*pred)(const Owner&)) && {
    f_->written = [pred](const void* o) { return pred(*static_cast<const Owner*>(o)); };
    return std::move(*this);
  }
  // Written by the table but read by its section's reader, for the reason given (a path to resolve, a file to load).
  FieldDef readByCode(const char* reason) && {
    f_->read_by_code = reason;
    return std::move(*this);
  }
  operator std::shared_ptr<const SceneField>() && { return std::move(f_); }

 private:
  std::shared_ptr<SceneField> f_;
};

namespace fields {

namespace detail {

template <class Owner, class T>
const T& at(const void* o, T Owner::*m) {
  return static_cast<const Owner*>(o)->*m;
}
template <class Owner, class T>
T& at(void* o, T Owner::*m) {
  return static_cast<Owner*>(o)->*m;
}

// A value binding of `m`: `get` reads it from a reader (given the current value), `put` turns it into JSON.
template <class Owner, class T, class Get, class Put>
FieldDef<Owner> value(const char* type, T Owner::*m, FieldRule rule, Get get, Put put) {
  auto f = std::make_shared<SceneField>();
  f->type = type;
  f->owner = &typeid(Owner);
  f->rule = rule;
  f->read = [m, get, rule](const scene_json::ObjectReader& r, const std::string& key, void* o) {
    T& v = at(o, m);
    v = get(r, key, v, rule);
  };
  f->write = [m, put](const void* o, const std::string& key, SceneJson& j) { j[key] = put(at(o, m)); };
  f->text = [m, put](const void* o) {
    const SceneJson v = put(at(o, m));
    return v.is_string() ? v.template get<std::string>() : v.dump();
  };
  f->write_default = [m, put](const std::string& key, SceneJson& j) {
    const Owner fresh{};
    j[key] = put(fresh.*m);
  };
  return FieldDef<Owner>(std::move(f));
}

double readNumber(const scene_json::ObjectReader& r, const std::string& key, double current, const FieldRule& rule);
long long readInteger(const scene_json::ObjectReader& r, const std::string& key, long long current, long long max,
                      const FieldRule& rule);
Vec3d readVec3(const scene_json::ObjectReader& r, const std::string& key, const Vec3d& current, const FieldRule& rule);
std::string readText(const scene_json::ObjectReader& r, const std::string& key, const std::string& current,
                     const FieldRule& rule);
inline SceneJson vec3Json(const Vec3d& v) { return SceneJson::array({v.x, v.y, v.z}); }

template <class Owner, class C>
std::shared_ptr<SceneField> arrayField(std::vector<C> Owner::*m) {
  auto f = std::make_shared<SceneField>();
  f->shape = SceneField::Shape::kArray;
  f->type = "array";
  f->owner = &typeid(Owner);
  f->element = &typeid(C);
  f->child = [m](const void* o, std::size_t i) -> const void* { return &at(o, m).at(i); };
  f->count = [m](const void* o) { return at(o, m).size(); };
  return f;
}

}  // namespace detail

template <class Owner>
FieldDef<Owner> number(double Owner::*m, FieldRule rule = {}) {
  return detail::value("number", m, std::move(rule), detail::readNumber, [](double v) { return SceneJson(v); });
}

// An integer field (int, unsigned) with its range; "is too large" past the type's maximum.
template <class Owner, class T>
FieldDef<Owner> integer(T Owner::*m, FieldRule rule) {
  static_assert(std::is_integral<T>::value, "integer() binds an integer field");
  if (rule.kind != FieldRule::Kind::kAtLeast && rule.kind != FieldRule::Kind::kInterval)
    throw std::logic_error("scene key table: an integer key needs a range (atLeast or interval)");
  auto get = [](const scene_json::ObjectReader& r, const std::string& key, T current, const FieldRule& rl) {
    return static_cast<T>(
        detail::readInteger(r, key, current, static_cast<long long>(std::numeric_limits<T>::max()), rl));
  };
  return detail::value("integer", m, std::move(rule), get, [](T v) { return SceneJson(v); });
}

template <class Owner>
FieldDef<Owner> boolean(bool Owner::*m) {
  auto get = [](const scene_json::ObjectReader& r, const std::string& key, bool current, const FieldRule&) {
    return r.boolean(key, current);
  };
  return detail::value("boolean", m, FieldRule{}, get, [](bool v) { return SceneJson(v); });
}

template <class Owner>
FieldDef<Owner> text(std::string Owner::*m) {
  return detail::value("string", m, FieldRule{}, detail::readText, [](const std::string& v) { return SceneJson(v); });
}

// A string that must be one of `choices` (did-you-mean on a near miss).
template <class Owner>
FieldDef<Owner> choice(std::string Owner::*m, std::vector<std::string> choices) {
  FieldRule rule;
  rule.kind = FieldRule::Kind::kChoice;
  rule.choices = std::move(choices);
  return detail::value("string", m, std::move(rule), detail::readText,
                       [](const std::string& v) { return SceneJson(v); });
}

// An enum read as one of its names (several names may map to one value: "float64", "double"); written as the
// first name of its value.
template <class Owner, class E>
FieldDef<Owner> choiceOf(E Owner::*m, std::vector<std::pair<const char*, E>> names) {
  FieldRule rule;
  rule.kind = FieldRule::Kind::kChoice;
  for (const auto& n : names) rule.choices.push_back(n.first);
  auto name = [names](E v) -> std::string {
    for (const auto& n : names)
      if (n.second == v) return n.first;
    return "?";
  };
  auto get = [names, name](const scene_json::ObjectReader& r, const std::string& key, E current, const FieldRule& rl) {
    const std::string s = detail::readText(r, key, name(current), rl);
    for (const auto& n : names)
      if (s == n.first) return n.second;
    return current;  // unreachable: readText accepted only a listed name
  };
  return detail::value("string", m, std::move(rule), get, [name](E v) { return SceneJson(name(v)); });
}

template <class Owner>
FieldDef<Owner> vec3(Vec3d Owner::*m, FieldRule rule = {}) {
  return detail::value("vec3", m, std::move(rule), detail::readVec3, detail::vec3Json);
}

// An object key whose keys are the rows under it, held in the parent's struct at `m`.
template <class Owner, class C>
FieldDef<Owner> object(C Owner::*m) {
  auto f = std::make_shared<SceneField>();
  f->shape = SceneField::Shape::kObject;
  f->type = "object";
  f->owner = &typeid(Owner);
  f->element = &typeid(C);
  f->child = [m](const void* o, std::size_t) -> const void* { return &detail::at(o, m); };
  return FieldDef<Owner>(std::move(f));
}

// An object key held by the Scene itself rather than by its parent's struct (material.cutting: Scene::cut_thresholds,
// a haptic setting beside Material, not in it).
template <class C>
FieldDef<Scene> sceneObject(C Scene::*m) {
  auto f = std::make_shared<SceneField>();
  f->shape = SceneField::Shape::kObject;
  f->type = "object";
  f->owner = &typeid(Scene);
  f->element = &typeid(C);
  f->of_scene = true;
  f->child = [m](const void* scene, std::size_t) -> const void* { return &detail::at(scene, m); };
  return FieldDef<Scene>(std::move(f));
}

// An array of objects, each element's keys the rows under "<path>[]".
template <class Owner, class C>
FieldDef<Owner> array(std::vector<C> Owner::*m) {
  return FieldDef<Owner>(detail::arrayField(m));
}

// An array written as a list when `listed`, else as its one element's keys in the parent object itself.
template <class Owner, class C>
FieldDef<Owner> arrayOrSingle(std::vector<C> Owner::*m, bool Owner::*listed) {
  std::shared_ptr<SceneField> f = detail::arrayField(m);
  f->as_single = [listed](const void* o) { return !detail::at(o, listed); };
  return FieldDef<Owner>(std::move(f));
}

}  // namespace fields

// The table's rows directly under `parent` with their names (sceneKeysUnder's order).
struct SceneRow {
  const SceneKey* key;
  std::string name;
};
std::vector<SceneRow> sceneRowsUnder(const std::string& parent);
// Whether `key` applies to an object of `kind` (its `kinds` is empty or names it).
bool sceneKeyUsedBy(const SceneKey& key, const std::string& kind);

// Reads the keys under `rows` ("geometry", "tools[]", "haptics.devices[]") that the table reads, from `r` into
// `obj`, absent keys keeping obj's values: first `kind` when some keys depend on it (then `on_kind(kind)`, and only
// that kind's keys after it), then every missing required key, then each key in table order, checked by its rule.
void readSceneKeys(const scene_json::ObjectReader& r, const std::string& rows, const std::type_info& type, void* obj,
                   const std::function<void(const std::string& kind)>& on_kind = {});
template <class T>
void readSceneKeys(const scene_json::ObjectReader& r, const std::string& rows, T& obj,
                   const std::function<void(const std::string& kind)>& on_kind = {}) {
  readSceneKeys(r, rows, typeid(T), &obj, on_kind);
}

// The whole scene as JSON, walking the table: every row in table order, objects and arrays of objects included,
// a row with `kinds` only for its kinds, a row with a writer condition only when it holds.
SceneJson writeSceneKeys(const Scene& s);

}  // namespace inc
