// The range rules of scene key bindings, and the walks over the key table that read an object and write a scene.
#include "host/scene/scene_fields.h"

#include <cstdlib>

namespace inc {

using scene_json::formatNumber;
using scene_json::ObjectReader;

namespace {

std::string got(double v) { return " (got " + formatNumber(v) + ")"; }
std::string got(long long v) { return " (got " + std::to_string(v) + ")"; }

// The reason a value outside `rule` is refused, before its " (got v)".
std::string outside(const FieldRule& rule) {
  switch (rule.kind) {
    case FieldRule::Kind::kAbove: return "must be > " + formatNumber(rule.lo) + rule.note;
    case FieldRule::Kind::kAtLeast: return "must be >= " + formatNumber(rule.lo) + rule.note;
    case FieldRule::Kind::kInterval: return "must lie in " + rule.interval + rule.note;
    default: return "is out of range";
  }
}

}  // namespace

bool FieldRule::accepts(double v) const {
  switch (kind) {
    case Kind::kAbove: return v > lo;
    case Kind::kAtLeast: return v >= lo;
    case Kind::kInterval: return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
    default: return true;
  }
}

std::string FieldRule::text() const {
  switch (kind) {
    case Kind::kNone: return "";
    case Kind::kAbove: return "> " + formatNumber(lo);
    case Kind::kAtLeast: return ">= " + formatNumber(lo);
    case Kind::kInterval: return interval;
    case Kind::kEachAbove0: return "each > 0";
    case Kind::kUnit: return "non-zero; normalised on load";
    case Kind::kChoice: {
      std::string s;
      for (const std::string& c : choices) s += (s.empty() ? "" : ", ") + c;
      return s;
    }
  }
  return "";
}

FieldRule above(double lo, std::string note) {
  FieldRule r;
  r.kind = FieldRule::Kind::kAbove;
  r.lo = lo;
  r.note = std::move(note);
  return r;
}

FieldRule atLeast(double lo) {
  FieldRule r;
  r.kind = FieldRule::Kind::kAtLeast;
  r.lo = lo;
  return r;
}

FieldRule interval(const std::string& text, std::string note) {
  // "[lo, hi)": a bracket, two numbers split by ", ", a bracket.
  const std::size_t comma = text.find(", ");
  if (text.size() < 5 || (text.front() != '[' && text.front() != '(') || (text.back() != ']' && text.back() != ')') ||
      comma == std::string::npos)
    throw std::logic_error("scene key table: bad interval \"" + text + "\"");
  FieldRule r;
  r.kind = FieldRule::Kind::kInterval;
  r.interval = text;
  r.note = std::move(note);
  r.lo_open = text.front() == '(';
  r.hi_open = text.back() == ')';
  r.lo = std::strtod(text.substr(1, comma - 1).c_str(), nullptr);
  r.hi = std::strtod(text.substr(comma + 2, text.size() - comma - 3).c_str(), nullptr);
  return r;
}

FieldRule eachAbove0() {
  FieldRule r;
  r.kind = FieldRule::Kind::kEachAbove0;
  return r;
}

FieldRule unitVector(std::string zero_reason, std::string huge_reason) {
  FieldRule r;
  r.kind = FieldRule::Kind::kUnit;
  r.zero_reason = std::move(zero_reason);
  r.huge_reason = std::move(huge_reason);
  return r;
}

namespace fields {
namespace detail {

double readNumber(const ObjectReader& r, const std::string& key, double current, const FieldRule& rule) {
  const double v = r.number(key, current);
  if (!rule.accepts(v)) r.fail(key, outside(rule) + got(v));
  return v;
}

long long readInteger(const ObjectReader& r, const std::string& key, long long current, long long max,
                      const FieldRule& rule) {
  const long long v = r.integer(key, current);
  if (!rule.accepts(static_cast<double>(v))) r.fail(key, outside(rule) + got(v));
  if (v > max) r.fail(key, "is too large" + got(v));
  return v;
}

Vec3d readVec3(const ObjectReader& r, const std::string& key, const Vec3d& current, const FieldRule& rule) {
  Vec3d v = r.vec3(key, current);
  if (rule.kind == FieldRule::Kind::kEachAbove0) {
    for (int c = 0; c < 3; ++c) {
      if (!(v[c] > 0))
        r.fail(key, "every component must be > 0 (component " + std::to_string(c) + " is " + formatNumber(v[c]) + ")");
    }
  }
  if (rule.kind == FieldRule::Kind::kUnit) {
    const double n2 = norm2(v);
    if (!(n2 > 0)) r.fail(key, rule.zero_reason);
    if (!std::isfinite(n2)) r.fail(key, rule.huge_reason);
    // A vector that is unit to rounding stays as it is, so that writing and re-reading a scene changes nothing.
    if (std::fabs(n2 - 1.0) > 8 * std::numeric_limits<double>::epsilon()) v = v * (1.0 / std::sqrt(n2));
  }
  return v;
}

std::string readText(const ObjectReader& r, const std::string& key, const std::string& current, const FieldRule& rule) {
  if (rule.kind == FieldRule::Kind::kChoice) return r.choice(key, current, rule.choices);
  return r.string(key, current);
}

}  // namespace detail
}  // namespace fields

namespace {

[[noreturn]] void tableError(const SceneKey& k, const std::string& what) {
  throw std::logic_error(std::string("scene key table: ") + k.path + " " + what);
}

const SceneField& fieldOf(const SceneKey& k) {
  if (!k.field) tableError(k, "has no binding");
  return *k.field;
}

void writeObject(const std::string& rows, const void* obj, const std::type_info& type, const Scene& root,
                 SceneJson& j) {
  std::string kind;  // the object's kind once its "kind" key is written
  for (const SceneRow& row : sceneRowsUnder(rows)) {
    const SceneField& f = fieldOf(*row.key);
    if (row.key->kinds[0] != '\0' && !kind.empty() && !sceneKeyUsedBy(*row.key, kind)) continue;
    const void* owner = f.of_scene ? &root : obj;
    if (*f.owner != (f.of_scene ? typeid(Scene) : type)) tableError(*row.key, "binds a field of another struct");
    if (!f.writtenFor(owner)) continue;
    const std::string path = scene_json::joinPath(rows, row.name);
    switch (f.shape) {
      case SceneField::Shape::kValue:
        f.write(owner, row.name, j);
        if (row.name == "kind") kind = f.text(owner);
        break;
      case SceneField::Shape::kObject: {
        SceneJson c = SceneJson::object();
        writeObject(path, f.child(owner, 0), *f.element, root, c);
        j[row.name] = std::move(c);
        break;
      }
      case SceneField::Shape::kArray: {
        if (f.asSingle(owner)) {  // the one element's keys in this object itself
          writeObject(path + "[]", f.child(owner, 0), *f.element, root, j);
          break;
        }
        SceneJson a = SceneJson::array();
        for (std::size_t i = 0; i < f.count(owner); ++i) {
          SceneJson e = SceneJson::object();
          writeObject(path + "[]", f.child(owner, i), *f.element, root, e);
          a.push_back(std::move(e));
        }
        j[row.name] = std::move(a);
        break;
      }
    }
  }
}

}  // namespace

void readSceneKeys(const ObjectReader& r, const std::string& rows, const std::type_info& type, void* obj,
                   const std::function<void(const std::string& kind)>& on_kind) {
  const std::vector<SceneRow> under = sceneRowsUnder(rows);
  auto readable = [](const SceneRow& row) {
    const SceneField& f = fieldOf(*row.key);
    return f.shape == SceneField::Shape::kValue && !f.read_by_code;
  };
  auto read = [&](const SceneRow& row) {
    const SceneField& f = *row.key->field;
    if (*f.owner != type) tableError(*row.key, "binds a field of another struct");
    f.read(r, row.name, obj);
  };
  auto require = [&](const SceneRow& row) {
    const char* hint = row.key->field->required;
    if (hint && !r.has(row.name)) r.fail(row.name, std::string("is required (") + hint + ")");
  };
  // When some keys belong to some kinds only, the kind comes first and picks them.
  const SceneRow* kind_row = nullptr;
  for (const SceneRow& row : under)
    if (row.key->kinds[0] != '\0') kind_row = &row;
  if (kind_row) {
    kind_row = nullptr;
    for (const SceneRow& row : under)
      if (row.name == "kind" && readable(row)) kind_row = &row;
  }
  std::string kind;
  if (kind_row) {
    require(*kind_row);
    read(*kind_row);
    kind = kind_row->key->field->text(obj);
    if (on_kind) on_kind(kind);
  }
  auto applies = [&](const SceneRow& row) {
    return &row != kind_row && readable(row) && (kind.empty() || sceneKeyUsedBy(*row.key, kind));
  };
  for (const SceneRow& row : under)
    if (applies(row)) require(row);
  for (const SceneRow& row : under)
    if (applies(row)) read(row);
}

SceneJson writeSceneKeys(const Scene& s) {
  SceneJson j = SceneJson::object();
  writeObject("", &s, typeid(Scene), s, j);
  return j;
}

}  // namespace inc
