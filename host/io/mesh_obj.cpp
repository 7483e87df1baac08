// Wavefront OBJ reader: v and f statements (v, v/vt, v//vn, v/vt/vn; negative indices), polygons fan-triangulated.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "host/io/mesh_formats.h"
#include "model/input_error.h"

namespace inc {
namespace mesh_formats {

namespace {

struct FaceOrigin {
  std::size_t face;  // 1-based face number in the file
  std::size_t line;  // 1-based line number
};

std::string faceName(const FaceOrigin& o) {
  return "face " + std::to_string(o.face) + " (line " + std::to_string(o.line) + ")";
}

}  // namespace

TriangleMesh readObj(const std::string& text, const std::string& file) {
  TriangleMesh mesh;
  std::vector<FaceOrigin> origin;  // per triangle, for index errors found after all vertices are known
  std::vector<std::string_view> tok;
  std::vector<int> polygon;
  std::vector<long long> raw;  // 1-based absolute indices of the current face
  std::size_t line_no = 0, face_no = 0, pos = 0;

  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    splitTokens(line, tok);
    if (tok.empty()) continue;

    if (tok[0] == "v") {
      const std::string where =
          "vertex " + std::to_string(mesh.vertices.size() + 1) + " (line " + std::to_string(line_no) + ")";
      if (tok.size() < 4) throw InputError(file, where, "a vertex needs three coordinates");
      double x[3];
      for (int c = 0; c < 3; ++c) {
        if (!parseDouble(tok[1 + c], x[c]))
          throw InputError(file, where, "'" + std::string(tok[1 + c]) + "' is not a number");
        if (!std::isfinite(x[c])) throw InputError(file, where, "coordinate is not finite (NaN or infinite)");
      }
      mesh.vertices.push_back(Vec3d(x[0], x[1], x[2]));
    } else if (tok[0] == "f") {
      ++face_no;
      const FaceOrigin o{face_no, line_no};
      if (tok.size() < 4) {
        throw InputError(file, faceName(o), "a face needs at least 3 vertices, got " + std::to_string(tok.size() - 1));
      }
      raw.clear();
      for (std::size_t k = 1; k < tok.size(); ++k) {
        std::string_view ref = tok[k];
        const std::size_t slash = ref.find('/');
        if (slash != std::string_view::npos) ref = ref.substr(0, slash);
        long long idx = 0;
        if (!parseInteger(ref, idx))
          throw InputError(file, faceName(o), "'" + std::string(tok[k]) + "' is not a vertex reference");
        if (idx == 0) throw InputError(file, faceName(o), "vertex index 0 is invalid (OBJ indices start at 1)");
        if (idx < 0) {
          // Relative: -1 is the last vertex defined so far.
          const long long abs_idx = static_cast<long long>(mesh.vertices.size()) + 1 + idx;
          if (abs_idx < 1) {
            throw InputError(file, faceName(o),
                             "relative vertex index " + std::to_string(idx) + " reaches before the first vertex (" +
                                 std::to_string(mesh.vertices.size()) + " defined so far)");
          }
          idx = abs_idx;
        }
        raw.push_back(idx);
      }
      polygon.clear();
      for (long long idx : raw) {
        // Positive indices may refer to vertices defined later in the file; their range is checked at the end.
        if (idx > std::numeric_limits<int>::max())
          throw InputError(file, faceName(o), "vertex index " + std::to_string(idx) + " is out of range");
        polygon.push_back(static_cast<int>(idx - 1));
      }
      fanTriangulate(polygon, mesh.triangles);
      origin.resize(mesh.triangles.size(), o);
    }
    // vt, vn, vp, g, o, s, l, p, usemtl, mtllib and other statements carry nothing this program uses.
  }

  const long long n = static_cast<long long>(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      const long long v = mesh.triangles[t][c];
      if (v >= n) {
        throw InputError(file, faceName(origin[t]),
                         "vertex index " + std::to_string(v + 1) + " is out of range (the file has " +
                             std::to_string(n) + " vertices)");
      }
    }
  }
  return mesh;
}

}  // namespace mesh_formats
}  // namespace inc
