// Format readers behind loadMesh (OBJ, PLY, STL) and the small text helpers they share; internal to host/mesh_*.cpp.
#pragma once

#include <cstddef>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "host/io/mesh.h"

namespace inc {
namespace mesh_formats {

// Each reader parses the whole file content into triangles (polygons fan-triangulated) and throws
// InputError(file, element, reason) where `element` names what is wrong: "vertex 12 (line 40)", "face 7".
TriangleMesh readObj(const std::string& text, const std::string& file);
TriangleMesh readPly(const std::string& bytes, const std::string& file);
TriangleMesh readStl(const std::string& bytes, const std::string& file);

// Parses a whole token as a double (no locale, optional leading '+'); false when it is not a number.
// Values that overflow a double come back as +-infinity so callers report them as non-finite.
bool parseDouble(std::string_view token, double& out);
// Parses a whole token as a decimal integer; false when it is not one or does not fit in long long.
bool parseInteger(std::string_view token, long long& out);

// Splits a line into whitespace-separated tokens.
void splitTokens(std::string_view line, std::vector<std::string_view>& tokens);

// Appends the fan triangulation (p0, pi, pi+1) of a polygon with at least three corners.
void fanTriangulate(const std::vector<int>& polygon, std::vector<std::array<int, 3>>& triangles);

// A file opened for writing whose failures (cannot create, disk full) become InputError(path, "", reason).
class OutputFile {
 public:
  explicit OutputFile(const std::string& path);  // throws when the file cannot be created
  std::ofstream& stream() { return out_; }
  // Appends the shortest text that reads back to exactly `v` (no locale).
  void number(double v);
  void number(float v);
  void close();  // flushes; throws when anything failed to be written

 private:
  std::string path_;
  std::ofstream out_;
};

}  // namespace mesh_formats
}  // namespace inc
