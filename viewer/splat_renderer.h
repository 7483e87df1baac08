// Point splatting on the GPU (MFS Heller-myotomy paper, section 3): object-space Gaussian discs drawn as
// screen-space sprites, a depth-offset visibility pass, additive blending within the depth window, and a
// normalising pass that writes the surface's colour, lighting and depth.
#pragma once

#include "viewer/gl_api.h"
#include "viewer/splat_raster.h"
#include "viewer/view_camera.h"

namespace inc::viewer {

// The instanced disc vertex shader (GLSL 330): uniforms u_proj, u_view, u_eye, u_forward, u_ortho; outputs
// v_st (disc coordinates / r), v_pos_view, v_normal_view (the splat's normal), v_colour.
const char* splatVertexSource();

class SplatRenderer {
 public:
  SplatRenderer();  // needs a current GL context
  ~SplatRenderer();
  SplatRenderer(const SplatRenderer&) = delete;
  SplatRenderer& operator=(const SplatRenderer&) = delete;

  void upload(const SplatCloud& cloud);
  // Draws into the framebuffer bound at the call (width x height pixels, the camera's size), depth-tested
  // against what it already holds and writing depth, so splats and meshes occlude each other correctly.
  // The same maths as rasterizeSplats (splat_raster.h): per-pixel ray/disc depth, nearest-depth visibility,
  // Gaussian weights exp(-rho^2 / 2 sigma^2) summed over splats within depth_epsilon_m of it.
  void draw(const ViewCamera& cam, const SplatParams& params);
  std::size_t size() const { return count_; }
  // Issues the instanced quads (attributes 0-3 as in splatVertexSource) with whatever program is bound.
  void drawInstances() const;

 private:
  void ensureTargets(int w, int h);
  GLuint splat_program_ = 0, resolve_program_ = 0;
  GLuint vao_ = 0, instance_vbo_ = 0, empty_vao_ = 0;
  GLuint fbo_ = 0, accum_tex_ = 0, normal_tex_ = 0, depth_tex_ = 0;
  int target_w_ = 0, target_h_ = 0;
  std::size_t count_ = 0;
};

}  // namespace inc::viewer
