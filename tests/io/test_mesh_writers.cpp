// Tests for the PLY and legacy VTK writers: the bytes read back to exactly the values written.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "host/io/mesh.h"
#include "host/io/point_io.h"
#include "model/input_error.h"

using namespace inc;
namespace fs = std::filesystem;

namespace {

class PointIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("incision_pointio_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

std::string readAll(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

template <typename T>
T fromLittle(const std::string& bytes, std::size_t at) {
  using U = typename std::conditional<sizeof(T) == 4, std::uint32_t, std::uint64_t>::type;
  U u = 0;
  for (std::size_t i = 0; i < sizeof(U); ++i) u |= static_cast<U>(static_cast<unsigned char>(bytes[at + i])) << (8 * i);
  T v;
  std::memcpy(&v, &u, sizeof v);
  return v;
}

const std::vector<Vec3f> kPointsF = {Vec3f(0.1f, -2.0f, 3.5e-6f), Vec3f(1.0f / 3.0f, 0.0f, -0.0f), Vec3f(7, 8, 9)};
const std::vector<float> kStressF = {1.5f, 2.25f, -1e30f};
const std::vector<float> kDamageF = {0.0f, 0.5f, 1.0f};

}  // namespace

TEST_F(PointIo, BinaryPlyFloatReadsBackBitForBit) {
  writePointsPly<float>(path("p.ply"), kPointsF, {{"von_mises_pa", &kStressF}, {"damage", &kDamageF}});
  const std::string b = readAll(path("p.ply"));
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment Incision particles\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nproperty float von_mises_pa\nproperty float damage\nend_header\n";
  ASSERT_EQ(b.substr(0, header.size()), header);
  ASSERT_EQ(b.size(), header.size() + 3 * 5 * 4);
  for (std::size_t i = 0; i < 3; ++i) {
    const std::size_t at = header.size() + i * 20;
    EXPECT_EQ(fromLittle<float>(b, at + 0), kPointsF[i].x);
    EXPECT_EQ(fromLittle<float>(b, at + 4), kPointsF[i].y);
    EXPECT_EQ(fromLittle<float>(b, at + 8), kPointsF[i].z);
    EXPECT_EQ(fromLittle<float>(b, at + 12), kStressF[i]);
    EXPECT_EQ(fromLittle<float>(b, at + 16), kDamageF[i]);
  }
}

TEST_F(PointIo, AsciiPlyDoubleReadsBackExactly) {
  const std::vector<Vec3d> pts = {Vec3d(0.1, 1.0 / 3.0, -1e-300), Vec3d(2, 3, 4)};
  const std::vector<double> f = {3.14159, -2.0};
  writePointsPly<double>(path("a.ply"), pts, {{"my field!", &f}}, true);
  std::istringstream in(readAll(path("a.ply")));
  std::string line;
  std::vector<std::string> header;
  while (std::getline(in, line) && line != "end_header") header.push_back(line);
  EXPECT_EQ(header[1], "format ascii 1.0");
  EXPECT_EQ(header[3], "element vertex 2");
  EXPECT_EQ(header[4], "property double x");
  EXPECT_EQ(header[7], "property double my_field_");  // names are sanitised for viewers
  for (std::size_t i = 0; i < pts.size(); ++i) {
    double x, y, z, v;
    in >> x >> y >> z >> v;
    EXPECT_EQ(x, pts[i].x);
    EXPECT_EQ(y, pts[i].y);
    EXPECT_EQ(z, pts[i].z);
    EXPECT_EQ(v, f[i]);
  }
}

TEST_F(PointIo, VtkPointsHaveVertexCellsAndScalars) {
  writePointsVtk<float>(path("p.vtk"), kPointsF, {{"damage", &kDamageF}});
  std::istringstream in(readAll(path("p.vtk")));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "# vtk DataFile Version 3.0");
  std::getline(in, line);
  std::getline(in, line);
  EXPECT_EQ(line, "ASCII");
  std::getline(in, line);
  EXPECT_EQ(line, "DATASET POLYDATA");
  std::string word, type;
  std::size_t n = 0;
  in >> word >> n >> type;
  EXPECT_EQ(word, "POINTS");
  ASSERT_EQ(n, 3u);
  EXPECT_EQ(type, "float");
  for (const Vec3f& p : kPointsF) {
    float x, y, z;
    in >> x >> y >> z;
    EXPECT_EQ(x, p.x);
    EXPECT_EQ(y, p.y);
    EXPECT_EQ(z, p.z);
  }
  std::size_t cells = 0, ints = 0;
  in >> word >> cells >> ints;
  EXPECT_EQ(word, "VERTICES");
  EXPECT_EQ(cells, 3u);
  EXPECT_EQ(ints, 6u);
  for (std::size_t i = 0; i < 3; ++i) {
    std::size_t one, id;
    in >> one >> id;
    EXPECT_EQ(one, 1u);
    EXPECT_EQ(id, i);
  }
  std::string name, lut, def;
  int comps = 0;
  in >> word >> n >> type >> name >> type >> comps >> lut >> def;
  EXPECT_EQ(word, "POINT_DATA");
  EXPECT_EQ(n, 3u);
  EXPECT_EQ(name, "damage");
  EXPECT_EQ(comps, 1);
  EXPECT_EQ(lut, "LOOKUP_TABLE");
  for (float d : kDamageF) {
    float v;
    in >> v;
    EXPECT_EQ(v, d);
  }
}

TEST_F(PointIo, VtkMeshHasTrianglePolygons) {
  TriangleMesh m;
  m.vertices = {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0, 1, 0), Vec3d(0, 0, 1)};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  writeMeshVtk(path("m.vtk"), m);
  const std::string text = readAll(path("m.vtk"));
  const std::size_t at = text.find("POLYGONS 4 16\n");
  ASSERT_NE(at, std::string::npos) << text;
  std::istringstream in(text.substr(at + 14));
  for (const auto& t : m.triangles) {
    int three, a, b, c;
    in >> three >> a >> b >> c;
    EXPECT_EQ(three, 3);
    EXPECT_EQ((std::array<int, 3>{a, b, c}), t);
  }
  EXPECT_NE(text.find("POINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"), std::string::npos) << text;
}

TEST_F(PointIo, UnwritablePathIsAnInputErrorAndBadFieldLengthIsRefused) {
  const std::string bad = path("missing/folder/p.ply");
  try {
    writePointsPly<float>(bad, kPointsF);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), bad);
    EXPECT_NE(e.reason().find("cannot write"), std::string::npos) << e.what();
  }
  EXPECT_THROW(writePointsVtk<float>(path("missing/x.vtk"), kPointsF), InputError);
  EXPECT_THROW(writeMeshVtk(path("missing/x.vtk"), TriangleMesh{}), InputError);
  const std::vector<float> two = {1, 2};
  EXPECT_THROW(writePointsPly<float>(path("p.ply"), kPointsF, {{"short", &two}}), std::invalid_argument);
}
