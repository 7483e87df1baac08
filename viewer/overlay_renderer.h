// Flat-coloured overlays: translucent triangles (the swept cut surface) and force arrows facing the eye.
#pragma once

#include <array>
#include <vector>

#include "host/io/mesh.h"
#include "viewer/gl_api.h"
#include "viewer/view_camera.h"

namespace inc::viewer {

// World size of one pixel at point p (m): 2 half_height view depth / height in perspective, 2 half_height /
// height in orthographic views.
double pixelSizeAt(const ViewCamera& cam, const Vec3d& p);

// An arrow from `origin` to `tip` (world, m) as flat triangles in the plane through the segment that faces the
// eye: a shaft of width width_m and a head of width 3 width_m and length min(0.35 |tip - origin|, 4 width_m).
// Appends 3 vertices per triangle to `out`; nothing for a zero or view-aligned arrow.
void arrowTriangles(const ViewCamera& cam, const Vec3d& origin, const Vec3d& tip, double width_m,
                    std::vector<Vec3d>& out);

struct OverlayStyle {
  std::array<float, 4> rgba{1, 1, 1, 1};  // alpha < 1: blended over what is drawn (no depth write)
  bool depth_test = true;                 // false: drawn on top of everything
};

class OverlayRenderer {
 public:
  OverlayRenderer();  // needs a current GL context
  ~OverlayRenderer();
  OverlayRenderer(const OverlayRenderer&) = delete;
  OverlayRenderer& operator=(const OverlayRenderer&) = delete;

  // Triangles given as 3 vertices each (world, m), both sides, one colour.
  void draw(const ViewCamera& cam, const std::vector<Vec3d>& triangle_vertices, const OverlayStyle& style);
  void draw(const ViewCamera& cam, const TriangleMesh& mesh, const OverlayStyle& style);

 private:
  GLuint program_ = 0, vao_ = 0, vbo_ = 0;
};

}  // namespace inc::viewer
