// Tests for mesh loading (OBJ, PLY, STL), analyzeMesh facts and requireClosedMesh, on small files made here.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "host/io/mesh.h"
#include "model/input_error.h"
#include "tests/support/repo_paths.h"

using namespace inc;
namespace fs = std::filesystem;

namespace {

// A fresh folder per test under the system temp folder, removed afterwards.
class MeshIo : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("incision_mesh_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& bytes) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }
  fs::path dir_;
};

// Unit cube [0,1]^3 with outward quads, counter-clockwise seen from outside.
const char* kCubeVerts = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";
const int kCubeQuads[6][4] = {{1, 4, 3, 2}, {5, 6, 7, 8}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 4, 8, 7}, {4, 1, 5, 8}};

std::string cubeObj(bool skip_top = false) {
  std::string s = std::string("# unit cube\n") + kCubeVerts;
  for (int f = 0; f < 6; ++f) {
    if (skip_top && f == 1) continue;
    s += "f";
    for (int k = 0; k < 4; ++k) s += " " + std::to_string(kCubeQuads[f][k]);
    s += "\n";
  }
  return s;
}

TriangleMesh cubeMesh() {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.push_back(Vec3d(i == 1 || i == 2 || i == 5 || i == 6, i == 2 || i == 3 || i == 6 || i == 7, i >= 4));
  for (const auto& q : kCubeQuads) {
    m.triangles.push_back({q[0] - 1, q[1] - 1, q[2] - 1});
    m.triangles.push_back({q[0] - 1, q[2] - 1, q[3] - 1});
  }
  return m;
}

// Expects InputError whose key contains `key` and whose message contains `reason`.
void expectError(const std::function<void()>& f, const std::string& key, const std::string& reason) {
  try {
    f();
    ADD_FAILURE() << "expected InputError (key '" << key << "', reason '" << reason << "')";
  } catch (const InputError& e) {
    EXPECT_NE(e.key().find(key), std::string::npos) << "key: '" << e.key() << "' in: " << e.what();
    EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
  }
}

void appendLe(std::string& s, const void* p, std::size_t n) {
  // The tests build binary files byte by byte, least significant first, independent of the host.
  std::uint64_t u = 0;
  std::memcpy(&u, p, n);
  for (std::size_t i = 0; i < n; ++i) s.push_back(static_cast<char>((u >> (8 * i)) & 0xff));
}
template <typename T>
void le(std::string& s, T v) {
  appendLe(s, &v, sizeof v);
}
template <typename T>
void be(std::string& s, T v) {
  std::string tmp;
  le(tmp, v);
  s.append(tmp.rbegin(), tmp.rend());
}

std::string binaryStl(const TriangleMesh& m, const std::string& header80 = "binary cube") {
  std::string s = header80;
  s.resize(80, ' ');
  le<std::uint32_t>(s, static_cast<std::uint32_t>(m.triangles.size()));
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k) le<float>(s, 0.0f);  // normal, ignored
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) le<float>(s, static_cast<float>(m.vertices[t[c]][k]));
    le<std::uint16_t>(s, 0);
  }
  return s;
}

void expectUnitCube(const TriangleMesh& m) {
  ASSERT_EQ(m.vertices.size(), 8u);
  ASSERT_EQ(m.triangles.size(), 12u);
  const MeshReport r = analyzeMesh(m);
  EXPECT_NEAR(r.signed_volume, 1.0, 1e-12);
  EXPECT_NEAR(r.area, 6.0, 1e-12);
  EXPECT_TRUE(r.closed());
  EXPECT_TRUE(r.watertight());
  EXPECT_EQ(r.components, 1);
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// analyzeMesh facts on hand-made meshes.

TEST(MeshAnalyze, UnitCubeIsClosedWithVolumeOneAndAreaSix) {
  const TriangleMesh m = cubeMesh();
  const MeshReport r = analyzeMesh(m);
  EXPECT_EQ(r.vertex_count, 8);
  EXPECT_EQ(r.triangle_count, 12);
  EXPECT_EQ(r.boundary_edges, 0);
  EXPECT_EQ(r.non_manifold_edges, 0);
  EXPECT_EQ(r.inconsistent_edges, 0);
  EXPECT_EQ(r.degenerate_triangles, 0);
  EXPECT_EQ(r.components, 1);
  EXPECT_NEAR(r.signed_volume, 1.0, 1e-14);  // exact in binary arithmetic up to a few roundings
  EXPECT_NEAR(r.area, 6.0, 1e-14);
  EXPECT_TRUE(r.watertight());
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(r.bbox_min[c], 0.0);
    EXPECT_EQ(r.bbox_max[c], 1.0);
  }
  TriangleMesh copy = m;
  EXPECT_EQ(requireClosedMesh(copy, "cube.obj", "geometry.mesh"), "");
  EXPECT_EQ(copy.triangles, m.triangles);
}

TEST(MeshAnalyze, OpenBoxHasFourBoundaryEdgesAndIsRejected) {
  TriangleMesh m = cubeMesh();
  m.triangles.erase(m.triangles.begin() + 2, m.triangles.begin() + 4);  // remove the top quad (z = 1)
  const MeshReport r = analyzeMesh(m);
  EXPECT_EQ(r.boundary_edges, 4);
  EXPECT_EQ(r.non_manifold_edges, 0);
  EXPECT_FALSE(r.closed());
  EXPECT_NEAR(r.area, 5.0, 1e-14);
  expectError([&] { requireClosedMesh(m, "open.obj", "geometry.mesh"); }, "geometry.mesh", "open: 4 boundary edges");
}

TEST(MeshAnalyze, ThreeTrianglesOnOneEdgeAreNonManifold) {
  TriangleMesh m;
  m.vertices = {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0.5, 1, 0), Vec3d(0.5, -1, 0), Vec3d(0.5, 0, 1)};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const MeshReport r = analyzeMesh(m);
  EXPECT_EQ(r.non_manifold_edges, 1);
  EXPECT_EQ(r.boundary_edges, 6);
  EXPECT_FALSE(r.closed());
  expectError([&] { requireClosedMesh(m, "fin.obj", "geometry.mesh"); }, "geometry.mesh",
              "1 non-manifold edges shared by more than two triangles, e.g. the edge between vertices 0 and 1");
}

TEST(MeshAnalyze, FlippedCubeHasNegativeVolumeAndIsFlippedBackWithANote) {
  TriangleMesh m = cubeMesh();
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  const MeshReport r = analyzeMesh(m);
  EXPECT_NEAR(r.signed_volume, -1.0, 1e-14);
  EXPECT_TRUE(r.watertight());  // closed and consistent: only the sign is wrong
  const std::string note = requireClosedMesh(m, "inward.obj", "geometry.mesh");
  EXPECT_NE(note.find("oriented inward"), std::string::npos) << note;
  EXPECT_NE(note.find("flipped 12 triangles"), std::string::npos) << note;
  EXPECT_NEAR(analyzeMesh(m).signed_volume, 1.0, 1e-14);
  EXPECT_EQ(m.triangles, cubeMesh().triangles);
}

TEST(MeshAnalyze, OneFlippedTriangleMakesThreeInconsistentEdges) {
  TriangleMesh m = cubeMesh();
  std::swap(m.triangles[5][1], m.triangles[5][2]);
  const MeshReport r = analyzeMesh(m);
  EXPECT_EQ(r.inconsistent_edges, 3);
  EXPECT_TRUE(r.closed());
  EXPECT_FALSE(r.watertight());
  expectError([&] { requireClosedMesh(m, "bad.obj", "geometry.mesh"); }, "geometry.mesh",
              "inconsistently oriented: 3 edges");
}

TEST(MeshAnalyze, CountsDegenerateTrianglesAndComponents) {
  TriangleMesh m = cubeMesh();
  TriangleMesh second = cubeMesh();
  for (auto& p : second.vertices) p = p + Vec3d(5, 0, 0);
  for (auto& t : second.triangles) m.triangles.push_back({t[0] + 8, t[1] + 8, t[2] + 8});
  m.vertices.insert(m.vertices.end(), second.vertices.begin(), second.vertices.end());
  MeshReport r = analyzeMesh(m);
  EXPECT_EQ(r.components, 2);
  EXPECT_NEAR(r.signed_volume, 2.0, 1e-13);
  EXPECT_EQ(r.degenerate_triangles, 0);
  // A collinear sliver and a repeated index: both zero area.
  m.vertices.push_back(Vec3d(10, 0, 0));
  m.vertices.push_back(Vec3d(11, 0, 0));
  m.vertices.push_back(Vec3d(12, 0, 0));
  m.triangles.push_back({16, 17, 18});
  m.triangles.push_back({16, 16, 17});
  r = analyzeMesh(m);
  EXPECT_EQ(r.degenerate_triangles, 2);
  EXPECT_EQ(r.components, 3);
}

TEST(MeshAnalyze, InwardCavityInsideAnOutwardShellIsKept) {
  // A hollow body: outer cube [0,10]^3 outward, inner cube [4,5]^3 inward; volume 1000 - 1.
  TriangleMesh m = cubeMesh();
  for (auto& p : m.vertices) p = p * 10.0;
  TriangleMesh inner = cubeMesh();
  for (auto& t : inner.triangles) m.triangles.push_back({t[0] + 8, t[2] + 8, t[1] + 8});
  for (auto& p : inner.vertices) m.vertices.push_back(p + Vec3d(4, 4, 4));
  EXPECT_NEAR(analyzeMesh(m).signed_volume, 999.0, 1e-10);
  const auto before = m.triangles;
  EXPECT_EQ(requireClosedMesh(m, "hollow.obj", "geometry.mesh"), "");
  EXPECT_EQ(m.triangles, before);
}

TEST(MeshAnalyze, FlatDoubleSidedSheetEnclosesNoVolume) {
  TriangleMesh m;
  m.vertices = {Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0, 1, 0)};
  m.triangles = {{0, 1, 2}, {0, 2, 1}};
  EXPECT_TRUE(analyzeMesh(m).watertight());
  expectError([&] { requireClosedMesh(m, "sheet.obj", "geometry.mesh"); }, "geometry.mesh", "encloses no volume");
}

// ---------------------------------------------------------------------------------------------------------
// OBJ

TEST_F(MeshIo, ObjQuadsAreFanTriangulated) {
  const TriangleMesh m = loadMesh(write("cube.obj", cubeObj()));
  expectUnitCube(m);
  EXPECT_EQ(m.triangles, cubeMesh().triangles);
}

TEST_F(MeshIo, ObjReadsSlashFormsNegativeIndicesCommentsAndCrlf) {
  std::string s = "# comment line\r\nmtllib x.mtl\r\ng cube\r\n";
  s += std::string(kCubeVerts);
  s += "vt 0 0\nvn 0 0 1\ns 1\nusemtl m\n";
  // Each face uses a different reference form; the last ones count back from the 8th vertex.
  s += "f 1/1/1 4/1/1 3/1/1 2/1/1\n";
  s += "f 5//1 6//1 7//1 8//1   # trailing comment\n";
  s += "f 1/1 2/1 6/1 5/1\n";
  s += "f -7 -6 -2 -3\n";                  // 2 3 7 6
  s += "f -6/1/1 -5/1/1 -1/1/1 -2/1/1\n";  // 3 4 8 7
  s += "f 4 1 5 8\r\n";
  const TriangleMesh m = loadMesh(write("forms.obj", s));
  expectUnitCube(m);
  EXPECT_EQ(m.triangles, cubeMesh().triangles);
}

TEST_F(MeshIo, ObjErrorsNameTheElementAndLine) {
  expectError([&] { loadMesh(write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")); }, "vertex 3 (line 3)",
              "not finite");
  expectError([&] { loadMesh(write("inf.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n")); }, "vertex 2 (line 2)",
              "not finite");
  expectError([&] { loadMesh(write("word.obj", "v 0 zero 0\n")); }, "vertex 1 (line 1)", "'zero' is not a number");
  expectError([&] { loadMesh(write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\nf 1 2 40\n")); },
              "face 2 (line 6)", "vertex index 40 is out of range (the file has 3 vertices)");
  expectError([&] { loadMesh(write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")); }, "face 1 (line 4)",
              "index 0 is invalid");
  expectError([&] { loadMesh(write("rel.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n")); }, "face 1 (line 3)",
              "reaches before the first vertex");
  expectError([&] { loadMesh(write("two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n")); }, "face 1 (line 3)",
              "at least 3 vertices, got 2");
  expectError([&] { loadMesh(write("nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n")); }, "", "empty mesh: no faces");
  expectError([&] { loadMesh(write("comments.obj", "# nothing here\n")); }, "", "empty mesh: no vertices");
}

TEST_F(MeshIo, FileLevelErrors) {
  expectError([&] { loadMesh((dir_ / "absent.obj").string()); }, "", "no such file");
  fs::create_directories(dir_ / "folder.obj");
  expectError([&] { loadMesh((dir_ / "folder.obj").string()); }, "", "is a directory");
  expectError([&] { loadMesh(write("mesh.xyz", "v 0 0 0\n")); }, "", "unknown mesh format '.xyz'");
  expectError([&] { loadMesh(write("empty.stl", "")); }, "", "the mesh file is empty");
  try {
    loadMesh((dir_ / "absent.obj").string());
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), (dir_ / "absent.obj").string());
  }
}

TEST_F(MeshIo, WriteObjRoundTripsExactly) {
  TriangleMesh m = cubeMesh();
  m.vertices[3] = Vec3d(0.1, 1.0 / 3.0, -2.5e-7);  // values with no short decimal form
  const std::string p = (dir_ / "out.obj").string();
  writeObj(p, m);
  const TriangleMesh back = loadMesh(p);
  ASSERT_EQ(back.vertices.size(), m.vertices.size());
  for (std::size_t i = 0; i < m.vertices.size(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(back.vertices[i][c], m.vertices[i][c]);
  EXPECT_EQ(back.triangles, m.triangles);
  expectError([&] { writeObj((dir_ / "no" / "such" / "dir.obj").string(), m); }, "", "cannot write");
}

// ---------------------------------------------------------------------------------------------------------
// PLY

TEST_F(MeshIo, PlyAsciiWithQuadsExtraPropertiesAndElements) {
  std::string s =
      "ply\nformat ascii 1.0\ncomment made by a test\nelement vertex 8\nproperty float x\n"
      "property float y\nproperty float z\nproperty uchar red\nelement face 6\n"
      "property list uchar int vertex_indices\nproperty int flags\nelement edge 1\nproperty int vertex1\n"
      "property int vertex2\nend_header\n";
  const char* v[8] = {"0 0 0", "1 0 0", "1 1 0", "0 1 0", "0 0 1", "1 0 1", "1 1 1", "0 1 1"};
  for (const char* p : v) s += std::string(p) + " 255\n";
  for (const auto& q : kCubeQuads)
    s += "4 " + std::to_string(q[0] - 1) + " " + std::to_string(q[1] - 1) + " " + std::to_string(q[2] - 1) + " " +
         std::to_string(q[3] - 1) + " 7\n";
  s += "0 1\n";
  const TriangleMesh m = loadMesh(write("cube.ply", s));
  expectUnitCube(m);
  EXPECT_EQ(m.triangles, cubeMesh().triangles);
}

std::string binaryPlyCube(bool big_endian, bool doubles, int vertex_count_override = -1) {
  const TriangleMesh c = cubeMesh();
  std::string s = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\nelement vertex " + std::to_string(vertex_count_override >= 0 ? vertex_count_override : 8) +
                  "\n";
  const char* t = doubles ? "double" : "float";
  s += std::string("property ") + t + " x\nproperty " + t + " y\nproperty " + t +
       " z\nelement face 12\nproperty list uchar uint vertex_indices\nend_header\n";
  for (const Vec3d& p : c.vertices) {
    for (int k = 0; k < 3; ++k) {
      if (doubles)
        big_endian ? be<double>(s, p[k]) : le<double>(s, p[k]);
      else
        big_endian ? be<float>(s, static_cast<float>(p[k])) : le<float>(s, static_cast<float>(p[k]));
    }
  }
  for (const auto& tri : c.triangles) {
    s.push_back(3);
    for (int v : tri) big_endian ? be<std::uint32_t>(s, v) : le<std::uint32_t>(s, v);
  }
  return s;
}

TEST_F(MeshIo, PlyBinaryLittleAndBigEndian) {
  expectUnitCube(loadMesh(write("le_double.ply", binaryPlyCube(false, true))));
  expectUnitCube(loadMesh(write("le_float.ply", binaryPlyCube(false, false))));
  expectUnitCube(loadMesh(write("be_float.ply", binaryPlyCube(true, false))));
  EXPECT_EQ(loadMesh(write("le2.ply", binaryPlyCube(false, true))).triangles, cubeMesh().triangles);
}

TEST_F(MeshIo, PlyErrorsNameTheElement) {
  std::string truncated = binaryPlyCube(false, true);
  truncated.resize(truncated.size() - 20);
  expectError([&] { loadMesh(write("trunc.ply", truncated)); }, "face 10", "unexpected end of file");
  // A header that promises far more vertices than the file holds is refused before anything is allocated.
  expectError([&] { loadMesh(write("huge.ply", binaryPlyCube(false, true, 2000000000))); }, "element vertex",
              "too short");
  std::string nan = binaryPlyCube(false, true);
  const std::size_t body = nan.find("end_header\n") + 11;
  std::string q;
  le<double>(q, std::nan(""));
  nan.replace(body + 4 * 8, 8, q);  // vertex 1, y
  expectError([&] { loadMesh(write("nan.ply", nan)); }, "vertex 1", "not finite");
  std::string s =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n";
  expectError([&] { loadMesh(write("range.ply", s)); }, "face 0", "vertex index 9 is out of range");
  expectError([&] { loadMesh(write("hdr.ply", "ply\nformat ascii 1.0\nelement vertex 3\n")); }, "header",
              "no 'end_header'");
  expectError([&] { loadMesh(write("magic.ply", "plx\nend_header\n")); }, "header line 1", "not a PLY file");
  std::string word = s;
  word.replace(word.find("1 0 0\n"), 6, "1 z 0\n");
  expectError([&] { loadMesh(write("word.ply", word)); }, "vertex 1", "'z' is not a valid y value");
  std::string points =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n";
  expectError([&] { loadMesh(write("points.ply", points)); }, "header", "no face element");
}

// ---------------------------------------------------------------------------------------------------------
// STL

std::string asciiStl(const TriangleMesh& m) {
  std::string s = "solid cube\n";
  for (const auto& t : m.triangles) {
    s += "  facet normal 0 0 0\n    outer loop\n";
    for (int v : t) {
      char buf[128];
      std::snprintf(buf, sizeof buf, "      vertex %.17g %.17g %.17g\n", m.vertices[v].x, m.vertices[v].y,
                    m.vertices[v].z);
      s += buf;
    }
    s += "    endloop\n  endfacet\n";
  }
  return s + "endsolid cube\n";
}

TEST_F(MeshIo, StlAsciiAndBinaryAreWeldedExactly) {
  const TriangleMesh c = cubeMesh();
  const TriangleMesh a = loadMesh(write("cube_ascii.stl", asciiStl(c)));
  expectUnitCube(a);  // 36 corners welded into 8 vertices
  const TriangleMesh b = loadMesh(write("cube_bin.stl", binaryStl(c)));
  expectUnitCube(b);
  // A binary file whose 80-byte header starts with "solid" is still read as binary (size rule).
  expectUnitCube(loadMesh(write("cube_solid.stl", binaryStl(c, "solid but binary"))));
  // -0.0 and +0.0 are the same point; 1e-9 apart are not.
  TriangleMesh z = c;
  z.vertices.push_back(Vec3d(-0.0, -0.0, 0.0));
  z.triangles[0][0] = 8;
  EXPECT_EQ(loadMesh(write("zeros.stl", asciiStl(z))).vertices.size(), 8u);
  z.vertices[8] = Vec3d(1e-9, 0, 0);
  EXPECT_EQ(loadMesh(write("near.stl", asciiStl(z))).vertices.size(), 9u);
}

TEST_F(MeshIo, StlErrorsNameTheFacet) {
  std::string trunc = binaryStl(cubeMesh(), "binary");
  trunc.resize(trunc.size() - 30);
  expectError([&] { loadMesh(write("trunc.stl", trunc)); }, "header", "declares 12 triangles");
  expectError([&] { loadMesh(write("short.stl", "abc")); }, "header", "too short for a binary STL");
  std::string two =
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid x\n";
  expectError([&] { loadMesh(write("two.stl", two)); }, "facet 0 (line 7)", "needs 3 vertices, got 2");
  std::string nan = asciiStl(cubeMesh());
  nan.replace(nan.find("vertex 1 1 0"), 12, "vertex 1 nan 0");
  expectError([&] { loadMesh(write("nan.stl", nan)); }, "facet", "not finite");
  TriangleMesh c = cubeMesh();
  c.vertices[2].y = std::nan("");
  expectError([&] { loadMesh(write("nan_bin.stl", binaryStl(c))); }, "facet 0", "not finite");
}

// ---------------------------------------------------------------------------------------------------------
// The shared organ meshes (skipped when ../shared/organs is absent).

void checkOrgan(const char* name) {
  const std::string path = test::sharedPath(std::string("organs/") + name);
  if (!fs::exists(path)) GTEST_SKIP() << path << " is absent (shared organ meshes are not committed)";
  TriangleMesh m = loadMesh(path);
  const MeshReport r = analyzeMesh(m);
  std::printf(
      "[ organ ] %s: %d vertices, %d triangles, boundary %d, non-manifold %d, inconsistent %d, degenerate %d,"
      " components %d, signed volume %.6g, area %.6g, bbox (%.4g %.4g %.4g)-(%.4g %.4g %.4g), closed %s\n",
      name, r.vertex_count, r.triangle_count, r.boundary_edges, r.non_manifold_edges, r.inconsistent_edges,
      r.degenerate_triangles, r.components, r.signed_volume, r.area, r.bbox_min.x, r.bbox_min.y, r.bbox_min.z,
      r.bbox_max.x, r.bbox_max.y, r.bbox_max.z, r.closed() ? "yes" : "no");
  EXPECT_TRUE(r.closed());
  EXPECT_EQ(r.inconsistent_edges, 0);
  const std::string note = requireClosedMesh(m, path, "geometry.mesh");
  std::printf("[ organ ] %s: requireClosedMesh note: '%s'\n", name, note.c_str());
  EXPECT_GT(analyzeMesh(m).signed_volume, 0.0);
}

TEST(MeshOrgans, LiverSmoothIsClosed) { checkOrgan("liver-smooth.obj"); }
TEST(MeshOrgans, Liver2IsClosed) { checkOrgan("liver2.obj"); }
