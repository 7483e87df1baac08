// STL reader: ascii and binary triangle soups, welded into an indexed mesh by exact coordinate equality.
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include "host/io/mesh_formats.h"
#include "model/input_error.h"

namespace inc {
namespace mesh_formats {

namespace {

// Welds corners with exactly equal coordinates (-0 and +0 count as equal) into one vertex.
class Welder {
 public:
  int index(Vec3d p) {
    p = Vec3d(p.x + 0.0, p.y + 0.0, p.z + 0.0);  // -0.0 + 0.0 == +0.0: one key for both zeros
    Key k;
    std::memcpy(&k.b[0], &p.x, 8);
    std::memcpy(&k.b[1], &p.y, 8);
    std::memcpy(&k.b[2], &p.z, 8);
    auto it = map_.find(k);
    if (it != map_.end()) return it->second;
    const int id = static_cast<int>(vertices.size());
    vertices.push_back(p);
    map_.emplace(k, id);
    return id;
  }
  std::vector<Vec3d> vertices;

 private:
  struct Key {
    std::uint64_t b[3];
    bool operator==(const Key& o) const { return b[0] == o.b[0] && b[1] == o.b[1] && b[2] == o.b[2]; }
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = 1469598103934665603ull;
      for (std::uint64_t v : k.b) h = (h ^ v) * 1099511628211ull ^ (v >> 29);
      return static_cast<std::size_t>(h);
    }
  };
  std::unordered_map<Key, int, KeyHash> map_;
};

std::uint32_t readU32(const std::string& b, std::size_t at) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + i])) << (8 * i);
  return v;
}

float readF32(const std::string& b, std::size_t at) {
  const std::uint32_t u = readU32(b, at);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

void addTriangle(Welder& w, TriangleMesh& mesh, const Vec3d (&corner)[3], const std::string& file,
                 const std::string& where) {
  for (const Vec3d& c : corner)
    if (!isFinite(c)) throw InputError(file, where, "vertex coordinate is not finite (NaN or infinite)");
  mesh.triangles.push_back({w.index(corner[0]), w.index(corner[1]), w.index(corner[2])});
}

TriangleMesh readBinaryStl(const std::string& bytes, const std::string& file) {
  const std::uint32_t n = readU32(bytes, 80);
  const std::uint64_t need = 84ull + 50ull * n;
  if (bytes.size() < need) {
    throw InputError(file, "header",
                     "binary STL declares " + std::to_string(n) + " triangles (" + std::to_string(need) +
                         " bytes) but the file has " + std::to_string(bytes.size()) + " bytes (truncated?)");
  }
  Welder w;
  TriangleMesh mesh;
  mesh.triangles.reserve(n);
  for (std::uint32_t t = 0; t < n; ++t) {
    const std::size_t at = 84 + 50 * static_cast<std::size_t>(t) + 12;  // skip the facet normal
    Vec3d corner[3];
    for (int c = 0; c < 3; ++c) {
      corner[c] = Vec3d(readF32(bytes, at + 12 * c), readF32(bytes, at + 12 * c + 4), readF32(bytes, at + 12 * c + 8));
    }
    addTriangle(w, mesh, corner, file, "facet " + std::to_string(t));
  }
  mesh.vertices = std::move(w.vertices);
  return mesh;
}

TriangleMesh readAsciiStl(const std::string& text, const std::string& file) {
  Welder w;
  TriangleMesh mesh;
  std::vector<std::string_view> tok;
  std::size_t pos = 0, line_no = 0, facet = 0;
  bool in_facet = false;
  int corners = 0;
  Vec3d corner[3];
  std::string where;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    splitTokens(line, tok);
    if (tok.empty()) continue;
    const std::string at_line = " (line " + std::to_string(line_no) + ")";
    if (tok[0] == "facet") {
      if (in_facet) throw InputError(file, "facet " + std::to_string(facet) + at_line, "'facet' before 'endfacet'");
      in_facet = true;
      corners = 0;
      where = "facet " + std::to_string(facet);
    } else if (tok[0] == "vertex") {
      if (!in_facet) throw InputError(file, "line " + std::to_string(line_no), "'vertex' outside a facet");
      if (corners == 3) throw InputError(file, where + at_line, "a facet has more than 3 vertices");
      if (tok.size() != 4) throw InputError(file, where + at_line, "expected 'vertex x y z'");
      double x[3];
      for (int c = 0; c < 3; ++c) {
        if (!parseDouble(tok[1 + c], x[c]))
          throw InputError(file, where + at_line, "'" + std::string(tok[1 + c]) + "' is not a number");
      }
      corner[corners++] = Vec3d(x[0], x[1], x[2]);
    } else if (tok[0] == "endfacet") {
      if (!in_facet) throw InputError(file, "line " + std::to_string(line_no), "'endfacet' without 'facet'");
      if (corners != 3)
        throw InputError(file, where + at_line, "a facet needs 3 vertices, got " + std::to_string(corners));
      addTriangle(w, mesh, corner, file, where + at_line);
      in_facet = false;
      ++facet;
    } else if (tok[0] == "solid" || tok[0] == "endsolid" || tok[0] == "outer" || tok[0] == "endloop") {
      // Structure only; several solids in one file are read as one mesh.
    } else {
      throw InputError(file, "line " + std::to_string(line_no),
                       "unexpected '" + std::string(tok[0].substr(0, 40)) + "' in an ascii STL");
    }
  }
  if (in_facet) throw InputError(file, where, "unexpected end of file inside a facet (truncated?)");
  mesh.vertices = std::move(w.vertices);
  return mesh;
}

bool startsWithSolid(const std::string& bytes) {
  std::size_t i = 0;
  while (i < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[i]))) ++i;
  return bytes.compare(i, 5, "solid") == 0;
}

}  // namespace

TriangleMesh readStl(const std::string& bytes, const std::string& file) {
  // Binary STL files may also begin with "solid"; the size formula 84 + 50 n decides first.
  if (bytes.size() >= 84 && 84ull + 50ull * readU32(bytes, 80) == bytes.size()) return readBinaryStl(bytes, file);
  if (startsWithSolid(bytes)) return readAsciiStl(bytes, file);
  if (bytes.size() < 84) {
    throw InputError(file, "header",
                     "too short for a binary STL (" + std::to_string(bytes.size()) +
                         " bytes) and not an ascii STL (no 'solid' at the start)");
  }
  return readBinaryStl(bytes, file);  // trailing bytes after the declared triangles are ignored
}

}  // namespace mesh_formats
}  // namespace inc
