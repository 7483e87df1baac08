// loadMesh: reads a mesh file, picks the format reader by extension and checks what every format must satisfy.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <system_error>

#include "host/io/mesh.h"
#include "host/io/mesh_formats.h"
#include "model/input_error.h"

namespace inc {
namespace mesh_formats {

bool parseDouble(std::string_view token, double& out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* first = token.data();
  const char* last = token.data() + token.size();
  const auto r = std::from_chars(first, last, out);
  if (r.ptr != last) return false;
  if (r.ec == std::errc::result_out_of_range) {
    // Overflow (1e999) becomes +-infinity so the caller reports a non-finite coordinate; underflow becomes the
    // nearest representable value. strtod's result is used only for its magnitude class here, so the locale's
    // decimal point cannot change it.
    out = std::strtod(std::string(token).c_str(), nullptr);
    if (std::fabs(out) == HUGE_VAL) out = std::copysign(std::numeric_limits<double>::infinity(), out);
    return true;
  }
  return r.ec == std::errc();
}

bool parseInteger(std::string_view token, long long& out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* last = token.data() + token.size();
  const auto r = std::from_chars(token.data(), last, out);
  return r.ec == std::errc() && r.ptr == last;
}

void splitTokens(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t b = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > b) tokens.push_back(line.substr(b, i - b));
  }
}

void fanTriangulate(const std::vector<int>& polygon, std::vector<std::array<int, 3>>& triangles) {
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i) triangles.push_back({polygon[0], polygon[i], polygon[i + 1]});
}

}  // namespace mesh_formats

namespace {

std::string readWholeFile(const std::string& path) {
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st)) throw InputError(path, "", "cannot open mesh file: no such file");
  if (std::filesystem::is_directory(st)) throw InputError(path, "", "cannot read mesh file: it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", std::string("cannot open mesh file: ") + std::strerror(errno));
  std::ostringstream buf;
  buf << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "cannot read mesh file: read error");
  return buf.str();
}

std::string extensionOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

TriangleMesh loadMesh(const std::string& path) {
  const std::string ext = extensionOf(path);
  if (ext != ".obj" && ext != ".ply" && ext != ".stl") {
    throw InputError(path, "", "unknown mesh format '" + ext + "' (expected .obj, .ply or .stl)");
  }
  const std::string bytes = readWholeFile(path);
  if (bytes.empty()) throw InputError(path, "", "the mesh file is empty");

  TriangleMesh mesh;
  if (ext == ".obj") {
    mesh = mesh_formats::readObj(bytes, path);
  } else if (ext == ".ply") {
    mesh = mesh_formats::readPly(bytes, path);
  } else {
    mesh = mesh_formats::readStl(bytes, path);
  }

  // Facts every format must give; the readers check them element by element already, this is the backstop.
  if (mesh.vertices.empty()) throw InputError(path, "", "empty mesh: no vertices");
  if (mesh.triangles.empty()) throw InputError(path, "", "empty mesh: no faces");
  if (mesh.vertices.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw InputError(path, "", "too many vertices for 32-bit indices");
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!isFinite(mesh.vertices[i])) {
      throw InputError(path, "vertex " + std::to_string(i), "coordinate is not finite (NaN or infinite)");
    }
  }
  const int n = static_cast<int>(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      const int v = mesh.triangles[t][c];
      if (v < 0 || v >= n) {
        throw InputError(
            path, "triangle " + std::to_string(t),
            "vertex index " + std::to_string(v) + " out of range (the mesh has " + std::to_string(n) + " vertices)");
      }
    }
  }
  return mesh;
}

}  // namespace inc
