// PLY and legacy VTK writers for particles and triangle meshes (binary PLY little endian; VTK ascii).
#include "host/io/point_io.h"

#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "host/io/mesh_formats.h"

namespace inc {

namespace {

template <typename T>
const char* plyTypeName() {
  return sizeof(T) == 4 ? "float" : "double";
}

template <typename T>
const char* vtkTypeName() {
  return sizeof(T) == 4 ? "float" : "double";
}

// Property and array names: viewers split on whitespace, so keep [A-Za-z0-9_] only.
std::string safeName(const std::string& name) {
  std::string s = name.empty() ? std::string("field") : name;
  for (char& c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) c = '_';
  }
  return s;
}

template <typename T>
void checkFields(const std::vector<PointField<T>>& fields, std::size_t n) {
  for (const PointField<T>& f : fields) {
    if (f.values == nullptr || f.values->size() != n) {
      throw std::invalid_argument("point field '" + f.name + "' has " +
                                  std::to_string(f.values ? f.values->size() : 0) + " values for " + std::to_string(n) +
                                  " points");
    }
  }
}

// Little-endian bytes of an IEEE value, whatever the host's byte order.
template <typename T>
void putLittle(std::ofstream& o, T v) {
  using U = typename std::conditional<sizeof(T) == 4, std::uint32_t, std::uint64_t>::type;
  U u;
  std::memcpy(&u, &v, sizeof u);
  char b[sizeof(U)];
  for (std::size_t i = 0; i < sizeof(U); ++i) b[i] = static_cast<char>((u >> (8 * i)) & 0xff);
  o.write(b, sizeof b);
}

template <typename T>
void writeVtkPoints(mesh_formats::OutputFile& f, const std::vector<Vec3<T>>& positions) {
  std::ofstream& o = f.stream();
  o << "POINTS " << positions.size() << ' ' << vtkTypeName<T>() << '\n';
  for (const Vec3<T>& p : positions) {
    f.number(p.x);
    o << ' ';
    f.number(p.y);
    o << ' ';
    f.number(p.z);
    o << '\n';
  }
}

template <typename T>
void writeVtkScalars(mesh_formats::OutputFile& f, std::size_t n, const std::vector<PointField<T>>& fields) {
  if (fields.empty()) return;
  std::ofstream& o = f.stream();
  o << "POINT_DATA " << n << '\n';
  for (const PointField<T>& fld : fields) {
    o << "SCALARS " << safeName(fld.name) << ' ' << vtkTypeName<T>() << " 1\nLOOKUP_TABLE default\n";
    for (T v : *fld.values) {
      f.number(v);
      o << '\n';
    }
  }
}

}  // namespace

template <typename T>
void writePointsPly(const std::string& path, const std::vector<Vec3<T>>& positions,
                    const std::vector<PointField<T>>& fields, bool ascii) {
  checkFields(fields, positions.size());
  mesh_formats::OutputFile f(path);
  std::ofstream& o = f.stream();
  o << "ply\nformat " << (ascii ? "ascii" : "binary_little_endian") << " 1.0\ncomment Incision particles\n";
  o << "element vertex " << positions.size() << '\n';
  for (const char* axis : {"x", "y", "z"}) o << "property " << plyTypeName<T>() << ' ' << axis << '\n';
  for (const PointField<T>& fld : fields) o << "property " << plyTypeName<T>() << ' ' << safeName(fld.name) << '\n';
  o << "end_header\n";
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3<T>& p = positions[i];
    if (ascii) {
      f.number(p.x);
      o << ' ';
      f.number(p.y);
      o << ' ';
      f.number(p.z);
      for (const PointField<T>& fld : fields) {
        o << ' ';
        f.number((*fld.values)[i]);
      }
      o << '\n';
    } else {
      putLittle(o, p.x);
      putLittle(o, p.y);
      putLittle(o, p.z);
      for (const PointField<T>& fld : fields) putLittle(o, (*fld.values)[i]);
    }
  }
  f.close();
}

template <typename T>
void writePointsVtk(const std::string& path, const std::vector<Vec3<T>>& positions,
                    const std::vector<PointField<T>>& fields) {
  checkFields(fields, positions.size());
  mesh_formats::OutputFile f(path);
  std::ofstream& o = f.stream();
  o << "# vtk DataFile Version 3.0\nIncision particles\nASCII\nDATASET POLYDATA\n";
  writeVtkPoints(f, positions);
  // One vertex cell per point so that ParaView draws them without a glyph filter.
  o << "VERTICES " << positions.size() << ' ' << 2 * positions.size() << '\n';
  for (std::size_t i = 0; i < positions.size(); ++i) o << "1 " << i << '\n';
  writeVtkScalars(f, positions.size(), fields);
  f.close();
}

void writeMeshVtk(const std::string& path, const TriangleMesh& mesh, const std::vector<PointField<double>>& fields) {
  checkFields(fields, mesh.vertices.size());
  mesh_formats::OutputFile f(path);
  std::ofstream& o = f.stream();
  o << "# vtk DataFile Version 3.0\nIncision mesh\nASCII\nDATASET POLYDATA\n";
  writeVtkPoints(f, mesh.vertices);
  o << "POLYGONS " << mesh.triangles.size() << ' ' << 4 * mesh.triangles.size() << '\n';
  for (const auto& t : mesh.triangles) o << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  writeVtkScalars(f, mesh.vertices.size(), fields);
  f.close();
}

template void writePointsPly<float>(const std::string&, const std::vector<Vec3f>&,
                                    const std::vector<PointField<float>>&, bool);
template void writePointsPly<double>(const std::string&, const std::vector<Vec3d>&,
                                     const std::vector<PointField<double>>&, bool);
template void writePointsVtk<float>(const std::string&, const std::vector<Vec3f>&,
                                    const std::vector<PointField<float>>&);
template void writePointsVtk<double>(const std::string&, const std::vector<Vec3d>&,
                                     const std::vector<PointField<double>>&);

}  // namespace inc
