// Draws a triangle surface with per-vertex normals and Phong lighting (tissue outside, cut walls inside).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "host/io/mesh.h"
#include "viewer/gl_api.h"
#include "viewer/view_camera.h"

namespace inc::viewer {

// Area-weighted vertex normals (the sum of the triangles' cross products, normalised); vertices with no
// triangle or only degenerate ones get (0, 0, 0).
std::vector<Vec3d> vertexNormals(const TriangleMesh& mesh);

struct SurfaceStyle {
  std::array<float, 3> front{0.80f, 0.36f, 0.33f};  // outer tissue
  std::array<float, 3> back{0.55f, 0.10f, 0.12f};   // inner side: what a cut or a hole shows
  float specular = 0.25f;
  float shininess = 24.0f;
  bool wireframe = false;
  bool on_top = false;  // no depth test: shown through what is in front (the tool tip inside tissue)
};

class SurfaceRenderer {
 public:
  SurfaceRenderer();  // needs a current GL context
  ~SurfaceRenderer();
  SurfaceRenderer(const SurfaceRenderer&) = delete;
  SurfaceRenderer& operator=(const SurfaceRenderer&) = delete;

  // Re-uploads positions and recomputed normals (every frame while the model deforms). `cut_walls` (one
  // flag per triangle, or empty): flagged triangles are cut walls, drawn on both sides in the back colour.
  void upload(const TriangleMesh& mesh, const std::vector<std::uint8_t>& cut_walls = {});
  // model: placement of the mesh in the world (identity for organs; the tool's frame for tools).
  void draw(const ViewCamera& cam, const SurfaceStyle& style, const Mat4f& model = Mat4f::identity()) const;
  std::size_t triangleCount() const { return index_count_ / 3; }

 private:
  GLuint program_ = 0, vao_ = 0, vbo_ = 0, ebo_ = 0;
  GLsizei index_count_ = 0;
  GLsizei wall_index_count_ = 0;  // the last wall_index_count_ indices are cut-wall triangles
};

}  // namespace inc::viewer
