// Checked JSON reading for scene files: SAX pass for line/column, key path, overflow and duplicate keys; typed getters.
#include "host/scene/scene_json.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <set>

#include "model/input_error.h"

namespace inc {
namespace scene_json {

using nlohmann::json;

TextPosition positionOfByte(const std::string& text, std::size_t offset) {
  offset = std::min(offset, text.size());
  TextPosition p;
  std::size_t line_start = 0;
  for (std::size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++p.line;
      line_start = i + 1;
    }
  }
  p.column = offset - line_start + 1;
  return p;
}

std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string listOf(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) s += ", ";
    s += names[i];
  }
  return s;
}

}  // namespace

std::string closestKey(const std::string& key, const std::vector<std::string>& known) {
  const std::string k = lower(key);
  std::string best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (const std::string& cand : known) {
    const std::string c = lower(cand);
    std::size_t d = editDistance(k, c);
    // A key that is the known key without its unit suffix (or with a wrong one) is a likely slip too.
    if (k.size() >= 3 && (c.rfind(k, 0) == 0 || k.rfind(c, 0) == 0)) d = std::min<std::size_t>(d, 2);
    if (d < best_d) {
      best_d = d;
      best = cand;
    }
  }
  const std::size_t limit = std::max<std::size_t>(2, key.size() / 3);
  return best_d <= limit ? best : std::string();
}

// ---------------------------------------------------------------------------------------------------------
// SAX pass: tracks the key path so a parse error, an overflowing number or a repeated key can name it.
namespace {

struct Frame {
  bool is_array = false;
  long long index = -1;     // arrays: index of the element last started
  std::string key;          // objects: key last read
  bool value_done = false;  // objects: the value of `key` has been read completely
  std::set<std::string> seen;
};

class PathSax : public nlohmann::json_sax<json> {
 public:
  explicit PathSax(const std::string& text) : text_(text) {}

  bool null() override { return scalar(); }
  bool boolean(bool) override { return scalar(); }
  bool number_integer(number_integer_t) override { return scalar(); }
  bool number_unsigned(number_unsigned_t) override { return scalar(); }
  bool number_float(number_float_t v, const string_t& literal) override {
    value();
    if (!std::isfinite(v)) {  // defensive: the lexer reports overflow itself (error 406)
      fail_path = path(false);
      fail_reason = literal + " is not a finite number (it overflows a double)";
      return false;
    }
    done();
    return true;
  }
  bool string(string_t&) override { return scalar(); }
  bool binary(binary_t&) override { return scalar(); }
  bool start_object(std::size_t) override {
    if (!value() || tooDeep()) return false;
    stack_.push_back(Frame{});
    return true;
  }
  bool key(string_t& k) override {
    Frame& f = stack_.back();
    f.key = k;
    f.value_done = false;
    if (!f.seen.insert(k).second) {
      fail_path = path(false);
      fail_reason = "key '" + k + "' appears twice in the same object";
      return false;
    }
    return true;
  }
  bool end_object() override {
    stack_.pop_back();
    done();
    return true;
  }
  bool start_array(std::size_t) override {
    if (!value() || tooDeep()) return false;
    Frame f;
    f.is_array = true;
    stack_.push_back(f);
    return true;
  }
  bool end_array() override {
    stack_.pop_back();
    done();
    return true;
  }
  bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& ex) override {
    fail_path = path(true);
    // `position` counts the bytes read, the offending one included.
    const std::size_t at = position > 0 ? position - 1 : 0;
    const TextPosition p = positionOfByte(text_, at);
    const std::string where = "line " + std::to_string(p.line) + ", column " + std::to_string(p.column);
    if (ex.id == 406) {  // number overflow
      fail_reason = "number at " + where + " is not finite (it overflows a double): " + literalAround(at);
      return false;
    }
    std::string what = ex.what();
    const std::size_t s = what.find("syntax error");
    if (s != std::string::npos) {
      what = what.substr(s);
    } else {
      const std::size_t b = what.find("] ");
      if (b != std::string::npos) what = what.substr(b + 2);
    }
    fail_reason = "invalid JSON at " + where + ": " + what;
    std::string word = lower(literalAround(at));
    if (!word.empty() && (word[0] == '-' || word[0] == '+')) word = word.substr(1);
    auto near_literal = [&word](const std::string& full) {
      return full.rfind(word, 0) == 0 || word.rfind(full, 0) == 0;
    };
    if (!word.empty() && (near_literal("nan") || near_literal("infinity"))) {
      fail_reason += " (NaN and Infinity are not JSON numbers: every number in a scene must be finite)";
    }
    return false;
  }

  std::string fail_path, fail_reason;

 private:
  // A scene is a few levels deep; a document nested thousands deep would exhaust the stack of every recursive
  // walk after the parse (copies, destruction, error messages that print a value), so it stops here.
  bool tooDeep() {
    if (stack_.size() < kMaxSceneJsonDepth) return false;
    fail_path = path(false);
    fail_reason = "objects and arrays nest deeper than " + std::to_string(kMaxSceneJsonDepth) +
                  " levels here; a scene needs a handful";
    return true;
  }
  // Marks the start of a value: advances the index of an enclosing array.
  bool value() {
    if (!stack_.empty() && stack_.back().is_array) ++stack_.back().index;
    return true;
  }
  // Marks the end of a value: an error after it is no longer "in" its key.
  void done() {
    if (!stack_.empty() && !stack_.back().is_array) stack_.back().value_done = true;
  }
  bool scalar() {
    value();
    done();
    return true;
  }
  // The key path of the value being read; at a parse error an array's next element is the one that failed.
  std::string path(bool at_error) const {
    std::string p;
    for (std::size_t i = 0; i < stack_.size(); ++i) {
      const Frame& f = stack_[i];
      if (f.is_array) {
        long long idx = f.index;
        if (at_error && i + 1 == stack_.size()) ++idx;
        if (idx >= 0) p = indexPath(p, static_cast<std::size_t>(idx));
      } else if (!f.key.empty() && !(at_error && i + 1 == stack_.size() && f.value_done)) {
        p = joinPath(p, f.key);
      }
    }
    return p;
  }
  // The word (letters, digits, sign, dot) containing byte `at`: the offending literal.
  std::string literalAround(std::size_t at) const {
    if (at >= text_.size()) return "";
    auto in_word = [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.';
    };
    std::size_t b = at, e = at;
    while (b > 0 && in_word(text_[b - 1])) --b;
    while (e < text_.size() && in_word(text_[e])) ++e;
    return text_.substr(b, std::min<std::size_t>(e - b, 40));
  }

  const std::string& text_;
  std::vector<Frame> stack_;
};

}  // namespace

json parseChecked(const std::string& text, const std::string& file) {
  PathSax sax(text);
  if (!json::sax_parse(text, &sax)) throw InputError(file, sax.fail_path, sax.fail_reason);
  return json::parse(text);  // cannot fail: the SAX pass accepted the same text
}

std::string describeValue(const json& v) {
  std::string text = v.dump();
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  switch (v.type()) {
    case json::value_t::null: return "null";
    case json::value_t::boolean: return "a boolean (" + text + ")";
    case json::value_t::string: return "a string (" + text + ")";
    case json::value_t::object: return "an object";
    case json::value_t::array: return "an array";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float: return "a number (" + text + ")";
    default: return std::string("a ") + v.type_name();
  }
}

std::string joinPath(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

std::string indexPath(const std::string& parent, std::size_t index) {
  return parent + "[" + std::to_string(index) + "]";
}

std::string resolvePath(const std::string& path, const std::string& base_dir) {
  std::filesystem::path p(path);
  if (p.is_relative()) p = std::filesystem::path(base_dir.empty() ? "." : base_dir) / p;
  std::error_code ec;
  const std::filesystem::path abs = std::filesystem::absolute(p, ec);
  return (ec ? p : abs).lexically_normal().string();
}

double numberAt(const json& v, const std::string& file, const std::string& path) {
  if (v.is_string()) {
    // "nan", "inf", "-Infinity": a way to smuggle a non-finite number into JSON; say so plainly.
    std::string w = lower(v.get<std::string>());
    if (!w.empty() && (w[0] == '-' || w[0] == '+')) w = w.substr(1);
    if (w.rfind("nan", 0) == 0 || w.rfind("inf", 0) == 0) {
      throw InputError(file, path,
                       "expected a finite number, got " + describeValue(v) + ": NaN and infinity are not allowed");
    }
  }
  if (!v.is_number()) throw InputError(file, path, "expected a number, got " + describeValue(v));
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw InputError(file, path, "is not a finite number");
  return d;
}

Vec3d vec3At(const json& v, const std::string& file, const std::string& path) {
  if (!v.is_array()) throw InputError(file, path, "expected an array of 3 numbers, got " + describeValue(v));
  if (v.size() != 3)
    throw InputError(file, path, "expected an array of 3 numbers, got " + std::to_string(v.size()) + " elements");
  return Vec3d(numberAt(v[0], file, indexPath(path, 0)), numberAt(v[1], file, indexPath(path, 1)),
               numberAt(v[2], file, indexPath(path, 2)));
}

// ---------------------------------------------------------------------------------------------------------

ObjectReader::ObjectReader(const json& obj, std::string file, std::string path)
    : obj_(&obj), file_(std::move(file)), path_(std::move(path)) {
  if (!obj.is_object()) {
    throw InputError(file_, path_,
                     std::string(path_.empty() ? "the scene must be a JSON object" : "expected an object") + ", got " +
                         describeValue(obj));
  }
}

std::string ObjectReader::keyPath(const std::string& key) const { return joinPath(path_, key); }

void ObjectReader::fail(const std::string& key, const std::string& reason) const {
  throw InputError(file_, key.empty() ? path_ : keyPath(key), reason);
}

void ObjectReader::allowOnly(const std::vector<std::string>& known) const {
  for (auto it = obj_->begin(); it != obj_->end(); ++it) {
    if (std::find(known.begin(), known.end(), it.key()) != known.end()) continue;
    const std::string near = closestKey(it.key(), known);
    std::string reason = "unknown key '" + it.key() + "'";
    if (!near.empty()) {
      reason += "; did you mean '" + near + "'?";
    } else {
      reason += "; known keys" + std::string(path_.empty() ? "" : " here") + ": " + listOf(known);
    }
    fail(it.key(), reason);
  }
}

double ObjectReader::number(const std::string& key, double fallback) const {
  if (!has(key)) return fallback;
  return numberAt(obj_->at(key), file_, keyPath(key));
}

long long ObjectReader::integer(const std::string& key, long long fallback) const {
  if (!has(key)) return fallback;
  const json& v = obj_->at(key);
  if (v.is_number_integer()) {
    if (v.is_number_unsigned() &&
        v.get<unsigned long long>() > static_cast<unsigned long long>(std::numeric_limits<long long>::max()))
      fail(key, "integer " + v.dump() + " is too large");
    return v.get<long long>();
  }
  if (v.is_number_float()) {
    const double d = v.get<double>();
    // 4.0 is accepted as 4; 4.5 and 1e30 are not integers this program can hold.
    if (std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 9.0e15) return static_cast<long long>(d);
    fail(key, "expected an integer, got " + describeValue(v));
  }
  fail(key, "expected an integer, got " + describeValue(v));
}

bool ObjectReader::boolean(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const json& v = obj_->at(key);
  if (!v.is_boolean()) fail(key, "expected a boolean (true or false), got " + describeValue(v));
  return v.get<bool>();
}

std::string ObjectReader::string(const std::string& key, const std::string& fallback) const {
  if (!has(key)) return fallback;
  const json& v = obj_->at(key);
  if (!v.is_string()) fail(key, "expected a string, got " + describeValue(v));
  return v.get<std::string>();
}

std::string ObjectReader::choice(const std::string& key, const std::string& fallback,
                                 const std::vector<std::string>& choices) const {
  const std::string s = string(key, fallback);
  if (std::find(choices.begin(), choices.end(), s) != choices.end()) return s;
  std::string reason = "unknown value \"" + s + "\"";
  const std::string near = closestKey(s, choices);
  if (!near.empty()) reason += "; did you mean \"" + near + "\"?";
  reason += " (expected one of: " + listOf(choices) + ")";
  fail(key, reason);
}

Vec3d ObjectReader::vec3(const std::string& key, const Vec3d& fallback) const {
  if (!has(key)) return fallback;
  return vec3At(obj_->at(key), file_, keyPath(key));
}

ObjectReader ObjectReader::object(const std::string& key) const {
  if (!has(key)) fail(key, "is required");
  return ObjectReader(obj_->at(key), file_, keyPath(key));
}

const json* ObjectReader::array(const std::string& key) const {
  if (!has(key)) return nullptr;
  const json& v = obj_->at(key);
  if (!v.is_array()) fail(key, "expected an array, got " + describeValue(v));
  return &v;
}

}  // namespace scene_json
}  // namespace inc
