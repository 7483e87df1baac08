// Draws spheres (the metaball layer) as ray-cast impostors: exact silhouettes, shading and depth per pixel.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "physics/vec3.h"
#include "viewer/gl_api.h"
#include "viewer/view_camera.h"

namespace inc::viewer {

// Half-size of the square, centred on the sphere and facing the eye, that covers a sphere of radius r seen
// from distance d in perspective: the tangent cone (half-angle asin(r / d)) meets that plane at radius
// d r / sqrt(d^2 - r^2) (> r). Orthographic views need r. Returns 0 when the eye is inside the sphere.
double impostorHalfSize(double radius_m, double distance_m, bool orthographic);

class SphereRenderer {
 public:
  SphereRenderer();  // needs a current GL context
  ~SphereRenderer();
  SphereRenderer(const SphereRenderer&) = delete;
  SphereRenderer& operator=(const SphereRenderer&) = delete;

  // marks: one per sphere (or empty): 0 plain, 1 or 2 drawn in the marked colours (fixed, held spheres).
  void upload(const std::vector<Vec3d>& centres, const std::vector<double>& radii,
              const std::vector<std::uint8_t>& marks = {});
  // One quad per sphere; the fragment shader intersects the pixel's ray with the sphere, discards misses,
  // writes the hit's depth (so spheres intersect each other and the other layers correctly) and shades it
  // with the surface's headlight Phong (ambient 0.25, diffuse 0.75, specular 0.25, shininess 24).
  // colours[0] for plain spheres; with show_marks, colours[m] for spheres marked m.
  void draw(const ViewCamera& cam, const std::array<std::array<float, 3>, 3>& colours, bool show_marks) const;
  void draw(const ViewCamera& cam, const std::array<float, 3>& colour) const {
    draw(cam, {colour, colour, colour}, false);
  }
  std::size_t size() const { return count_; }

 private:
  GLuint program_ = 0, vao_ = 0, vbo_ = 0;
  std::size_t count_ = 0;
};

}  // namespace inc::viewer
