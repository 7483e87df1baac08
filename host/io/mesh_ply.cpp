// PLY reader: ascii and binary (little and big endian) bodies; vertex x/y/z of any scalar type, face index lists.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "host/io/mesh_formats.h"
#include "model/input_error.h"

namespace inc {
namespace mesh_formats {

namespace {

enum class PlyType { I8, U8, I16, U16, I32, U32, F32, F64 };
enum class PlyFormat { Ascii, BinaryLittle, BinaryBig };

bool plyTypeFromName(std::string_view s, PlyType& t) {
  if (s == "char" || s == "int8")
    t = PlyType::I8;
  else if (s == "uchar" || s == "uint8")
    t = PlyType::U8;
  else if (s == "short" || s == "int16")
    t = PlyType::I16;
  else if (s == "ushort" || s == "uint16")
    t = PlyType::U16;
  else if (s == "int" || s == "int32")
    t = PlyType::I32;
  else if (s == "uint" || s == "uint32")
    t = PlyType::U32;
  else if (s == "float" || s == "float32")
    t = PlyType::F32;
  else if (s == "double" || s == "float64")
    t = PlyType::F64;
  else
    return false;
  return true;
}

std::size_t plySize(PlyType t) {
  switch (t) {
    case PlyType::I8:
    case PlyType::U8: return 1;
    case PlyType::I16:
    case PlyType::U16: return 2;
    case PlyType::I32:
    case PlyType::U32:
    case PlyType::F32: return 4;
    case PlyType::F64: return 8;
  }
  return 8;
}

bool plyIntegral(PlyType t) { return t != PlyType::F32 && t != PlyType::F64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::F32;
  bool is_list = false;
  PlyType count_type = PlyType::U8;
};

struct PlyElement {
  std::string name;
  unsigned long long count = 0;
  std::vector<PlyProperty> props;
};

// Reads scalars from the body in file order, ascii tokens or binary values; never reads past the end.
class PlyBody {
 public:
  enum class Status { Ok, End, NotANumber };

  PlyBody(const std::string& bytes, std::size_t start, PlyFormat format)
      : bytes_(bytes), pos_(start), format_(format) {}

  std::size_t remaining() const { return bytes_.size() - std::min(pos_, bytes_.size()); }
  const std::string& badToken() const { return bad_; }

  Status read(PlyType t, double& out) {
    if (format_ == PlyFormat::Ascii) return readAscii(t, out);
    const std::size_t n = plySize(t);
    if (remaining() < n) return Status::End;
    unsigned char b[8];
    std::memcpy(b, bytes_.data() + pos_, n);
    pos_ += n;
    if (format_ == PlyFormat::BinaryBig) {
      for (std::size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    }
    // b now holds the value least significant byte first; assemble it without assuming the host's byte order.
    std::uint64_t u = 0;
    for (std::size_t i = 0; i < n; ++i) u |= static_cast<std::uint64_t>(b[i]) << (8 * i);
    switch (t) {
      case PlyType::I8: out = static_cast<std::int8_t>(u); break;
      case PlyType::U8: out = static_cast<std::uint8_t>(u); break;
      case PlyType::I16: out = static_cast<std::int16_t>(u); break;
      case PlyType::U16: out = static_cast<std::uint16_t>(u); break;
      case PlyType::I32: out = static_cast<std::int32_t>(u); break;
      case PlyType::U32: out = static_cast<std::uint32_t>(u); break;
      case PlyType::F32: {
        const std::uint32_t u32 = static_cast<std::uint32_t>(u);
        float f;
        std::memcpy(&f, &u32, 4);
        out = f;
        break;
      }
      case PlyType::F64: {
        double d;
        std::memcpy(&d, &u, 8);
        out = d;
        break;
      }
    }
    return Status::Ok;
  }

 private:
  Status readAscii(PlyType t, double& out) {
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    if (pos_ >= bytes_.size()) return Status::End;
    const std::size_t b = pos_;
    while (pos_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    const std::string_view tok(bytes_.data() + b, pos_ - b);
    if (!parseDouble(tok, out) || (plyIntegral(t) && std::isfinite(out) && out != std::floor(out))) {
      bad_ = std::string(tok.substr(0, 40));
      return Status::NotANumber;
    }
    return Status::Ok;
  }

  const std::string& bytes_;
  std::size_t pos_;
  PlyFormat format_;
  std::string bad_;
};

struct Header {
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  std::size_t body_start = 0;
};

Header parseHeader(const std::string& bytes, const std::string& file) {
  Header h;
  std::size_t pos = 0, line_no = 0;
  bool have_format = false;
  std::vector<std::string_view> tok;
  for (;;) {
    const std::size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) throw InputError(file, "header", "no 'end_header' line: the PLY header is truncated");
    std::string_view line(bytes.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::string where = "header line " + std::to_string(line_no);
    if (line_no == 1) {
      if (line != "ply") throw InputError(file, where, "not a PLY file (the first line must be 'ply')");
      continue;
    }
    splitTokens(line, tok);
    if (tok.empty()) continue;
    if (tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "end_header") break;
    if (tok[0] == "format") {
      if (tok.size() != 3)
        throw InputError(file, where, "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
      if (tok[1] == "ascii")
        h.format = PlyFormat::Ascii;
      else if (tok[1] == "binary_little_endian")
        h.format = PlyFormat::BinaryLittle;
      else if (tok[1] == "binary_big_endian")
        h.format = PlyFormat::BinaryBig;
      else
        throw InputError(file, where, "unknown PLY format '" + std::string(tok[1]) + "'");
      have_format = true;
    } else if (tok[0] == "element") {
      long long count = 0;
      if (tok.size() != 3 || !parseInteger(tok[2], count) || count < 0)
        throw InputError(file, where, "expected 'element <name> <count>' with a count >= 0");
      PlyElement e;
      e.name = std::string(tok[1]);
      e.count = static_cast<unsigned long long>(count);
      h.elements.push_back(e);
    } else if (tok[0] == "property") {
      if (h.elements.empty()) throw InputError(file, where, "a property before any element");
      PlyProperty p;
      if (tok.size() == 5 && tok[1] == "list") {
        p.is_list = true;
        if (!plyTypeFromName(tok[2], p.count_type) || !plyIntegral(p.count_type) || !plyTypeFromName(tok[3], p.type)) {
          throw InputError(file, where,
                           "bad list property types '" + std::string(tok[2]) + " " + std::string(tok[3]) + "'");
        }
        p.name = std::string(tok[4]);
      } else if (tok.size() == 3) {
        if (!plyTypeFromName(tok[1], p.type))
          throw InputError(file, where, "unknown property type '" + std::string(tok[1]) + "'");
        p.name = std::string(tok[2]);
      } else {
        throw InputError(file, where,
                         "expected 'property <type> <name>' or 'property list <count type> <type> <name>'");
      }
      h.elements.back().props.push_back(p);
    } else {
      throw InputError(file, where, "unknown header keyword '" + std::string(tok[0]) + "'");
    }
  }
  if (!have_format) throw InputError(file, "header", "no 'format' line");
  h.body_start = pos;
  return h;
}

int findProperty(const PlyElement& e, const char* name) {
  for (std::size_t i = 0; i < e.props.size(); ++i)
    if (e.props[i].name == name) return static_cast<int>(i);
  return -1;
}

// Smallest number of bytes one instance of the element can take in a binary body.
std::size_t minBinaryBytes(const PlyElement& e) {
  std::size_t n = 0;
  for (const PlyProperty& p : e.props) n += p.is_list ? plySize(p.count_type) : plySize(p.type);
  return n;
}

// Which properties of an element the reader uses: vertex coordinates x, y, z and the face index list.
struct ElementRole {
  bool is_vertex = false, is_face = false;
  int ix = -1, iy = -1, iz = -1, ilist = -1;  // property indices, -1 when unused
};

// Finds the properties of the vertex and face elements and checks their declarations.
ElementRole elementRole(const PlyElement& e, const std::string& file) {
  ElementRole r;
  r.is_vertex = e.name == "vertex";
  r.is_face = e.name == "face";
  if (r.is_vertex) {
    r.ix = findProperty(e, "x");
    r.iy = findProperty(e, "y");
    r.iz = findProperty(e, "z");
    if (r.ix < 0 || r.iy < 0 || r.iz < 0) throw InputError(file, "header", "element vertex lacks property x, y or z");
    for (int i : {r.ix, r.iy, r.iz})
      if (e.props[i].is_list) throw InputError(file, "header", "vertex property " + e.props[i].name + " is a list");
    if (e.count > static_cast<unsigned long long>(std::numeric_limits<int>::max()))
      throw InputError(file, "header", "too many vertices (" + std::to_string(e.count) + ") for 32-bit indices");
  }
  if (r.is_face) {
    r.ilist = findProperty(e, "vertex_indices");
    if (r.ilist < 0) r.ilist = findProperty(e, "vertex_index");
    if (r.ilist < 0 || !e.props[r.ilist].is_list)
      throw InputError(file, "header", "element face lacks the list property vertex_indices");
    if (!plyIntegral(e.props[r.ilist].type))
      throw InputError(file, "header", "face vertex_indices must have an integer type");
  }
  return r;
}

// Rejects counts the body cannot hold before reserving anything for them.
void requireBodyHolds(const PlyElement& e, PlyFormat format, const PlyBody& body, const std::string& file) {
  const std::size_t min_bytes =
      e.props.empty() ? 0 : (format == PlyFormat::Ascii ? 2 * e.props.size() - 1 : minBinaryBytes(e));
  if (min_bytes > 0 && e.count > body.remaining() / min_bytes + 1) {
    throw InputError(file, "element " + e.name,
                     "the header declares " + std::to_string(e.count) + " " + e.name + " elements but the file is " +
                         "too short to hold them (truncated?)");
  }
}

[[noreturn]] void throwReadFailure(PlyBody::Status s, const PlyBody& body, const PlyProperty& p,
                                   const std::string& file, const std::string& where) {
  if (s == PlyBody::Status::End) throw InputError(file, where, "unexpected end of file (truncated data)");
  throw InputError(file, where, "'" + body.badToken() + "' is not a valid " + p.name + " value");
}

// Reads one list property; its values are appended to `polygon` when it is the face's index list.
void readListProperty(PlyBody& body, const PlyProperty& p, PlyFormat format, bool indices, std::vector<int>& polygon,
                      const std::string& file, const std::string& where) {
  double v = 0;
  PlyBody::Status s = body.read(p.count_type, v);
  if (s != PlyBody::Status::Ok) throwReadFailure(s, body, p, file, where);
  if (!(v >= 0)) throw InputError(file, where, "invalid list length " + std::to_string(static_cast<long long>(v)));
  const std::size_t len = static_cast<std::size_t>(v);
  const std::size_t item = format == PlyFormat::Ascii ? 2 : plySize(p.type);
  if (len > body.remaining() / item + 1) throw InputError(file, where, "unexpected end of file (truncated data)");
  for (std::size_t j = 0; j < len; ++j) {
    s = body.read(p.type, v);
    if (s != PlyBody::Status::Ok) throwReadFailure(s, body, p, file, where);
    if (indices) {
      if (v < 0 || v > std::numeric_limits<int>::max())
        throw InputError(file, where, "vertex index " + std::to_string(static_cast<long long>(v)) + " is out of range");
      polygon.push_back(static_cast<int>(v));
    }
  }
  if (indices && len < 3) throw InputError(file, where, "a face needs at least 3 vertices, got " + std::to_string(len));
}

// Reads every property of one element instance: the coordinates go to xyz, the face's indices to polygon.
void readInstance(PlyBody& body, const PlyElement& e, const ElementRole& role, PlyFormat format, double xyz[3],
                  std::vector<int>& polygon, const std::string& file, const std::string& where) {
  for (std::size_t pi = 0; pi < e.props.size(); ++pi) {
    const PlyProperty& p = e.props[pi];
    if (p.is_list) {
      readListProperty(body, p, format, static_cast<int>(pi) == role.ilist, polygon, file, where);
      continue;
    }
    double v = 0;
    const PlyBody::Status s = body.read(p.type, v);
    if (s != PlyBody::Status::Ok) throwReadFailure(s, body, p, file, where);
    if (static_cast<int>(pi) == role.ix) xyz[0] = v;
    if (static_cast<int>(pi) == role.iy) xyz[1] = v;
    if (static_cast<int>(pi) == role.iz) xyz[2] = v;
  }
}

// Face indices refer to vertices that exist; `tri_face` names each triangle's face in the file.
void requireIndicesInRange(const TriangleMesh& mesh, const std::vector<std::size_t>& tri_face,
                           const std::string& file) {
  const int n = static_cast<int>(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      if (mesh.triangles[t][c] >= n) {
        throw InputError(file, "face " + std::to_string(tri_face[t]),
                         "vertex index " + std::to_string(mesh.triangles[t][c]) + " is out of range (the file has " +
                             std::to_string(n) + " vertices)");
      }
    }
  }
}

}  // namespace

TriangleMesh readPly(const std::string& bytes, const std::string& file) {
  const Header h = parseHeader(bytes, file);
  PlyBody body(bytes, h.body_start, h.format);
  TriangleMesh mesh;
  std::vector<std::size_t> tri_face;  // per triangle: 0-based face number in the file
  bool have_vertex = false, have_face = false;
  std::vector<int> polygon;

  for (const PlyElement& e : h.elements) {
    const ElementRole role = elementRole(e, file);
    have_vertex = have_vertex || role.is_vertex;
    have_face = have_face || role.is_face;
    const std::string singular = role.is_vertex ? "vertex" : (role.is_face ? "face" : e.name);
    requireBodyHolds(e, h.format, body, file);
    if (role.is_vertex) mesh.vertices.reserve(e.count);

    for (unsigned long long k = 0; k < e.count; ++k) {
      const std::string where = singular + " " + std::to_string(k);
      double xyz[3] = {0, 0, 0};
      polygon.clear();
      readInstance(body, e, role, h.format, xyz, polygon, file, where);
      if (role.is_vertex) {
        const Vec3d x(xyz[0], xyz[1], xyz[2]);
        if (!isFinite(x)) throw InputError(file, where, "coordinate is not finite (NaN or infinite)");
        mesh.vertices.push_back(x);
      }
      if (role.is_face) {
        fanTriangulate(polygon, mesh.triangles);
        tri_face.resize(mesh.triangles.size(), static_cast<std::size_t>(k));
      }
    }
  }
  if (!have_vertex) throw InputError(file, "header", "no vertex element");
  if (!have_face) throw InputError(file, "header", "no face element (a point cloud is not a surface mesh)");
  requireIndicesInRange(mesh, tri_face, file);
  return mesh;
}

}  // namespace mesh_formats
}  // namespace inc
