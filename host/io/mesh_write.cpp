// writeObj, and the checked output file that every mesh and point writer uses.
#include <cerrno>
#include <charconv>
#include <cstring>
#include <locale>

#include "host/io/mesh.h"
#include "host/io/mesh_formats.h"
#include "model/input_error.h"

namespace inc {
namespace mesh_formats {

OutputFile::OutputFile(const std::string& path) : path_(path) {
  errno = 0;
  out_.imbue(std::locale::classic());  // "1.5", never "1,5", whatever the global locale
  out_.open(path, std::ios::binary | std::ios::trunc);
  if (!out_) {
    const int err = errno;
    throw InputError(path, "", std::string("cannot write: ") + (err ? std::strerror(err) : "open failed"));
  }
}

void OutputFile::number(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out_.write(buf, r.ptr - buf);
}

void OutputFile::number(float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out_.write(buf, r.ptr - buf);
}

void OutputFile::close() {
  errno = 0;
  out_.flush();
  const bool ok = static_cast<bool>(out_);
  out_.close();
  if (!ok || out_.fail()) {
    const int err = errno;
    throw InputError(path_, "", std::string("cannot write: ") + (err ? std::strerror(err) : "write failed"));
  }
}

}  // namespace mesh_formats

void writeObj(const std::string& path, const TriangleMesh& mesh) {
  mesh_formats::OutputFile f(path);
  std::ofstream& o = f.stream();
  o << "# Incision mesh: " << mesh.vertices.size() << " vertices, " << mesh.triangles.size() << " triangles\n";
  for (const Vec3d& p : mesh.vertices) {
    o << "v ";
    f.number(p.x);
    o << ' ';
    f.number(p.y);
    o << ' ';
    f.number(p.z);
    o << '\n';
  }
  for (const auto& t : mesh.triangles) o << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  f.close();
}

}  // namespace inc
