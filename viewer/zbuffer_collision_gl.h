// The paper's z-buffer collision on the GPU: the split depth passes of zbuffer_collision.h drawn with OpenGL.
#pragma once

#include "viewer/gl_api.h"
#include "viewer/splat_renderer.h"
#include "viewer/zbuffer_collision.h"

namespace inc::viewer {

class ZBufferCollider {
 public:
  ZBufferCollider();  // needs a current GL context
  ~ZBufferCollider();
  ZBufferCollider(const ZBufferCollider&) = delete;
  ZBufferCollider& operator=(const ZBufferCollider&) = delete;

  // Renders the splats uploaded to `splats` twice from `cam` (toolAxisDepthCamera / cameraRayDepthCamera):
  // "before" keeps the farthest surface in front of the tip (depth test GREATER, fragments at or behind the
  // tip discarded), "after" the nearest one behind it (LESS, fragments in front discarded); fills `out`
  // like rasterizeTipDepth. Restores the caller's framebuffer binding and viewport.
  void render(const ViewCamera& cam, const SplatRenderer& splats, const Vec3d& tip, TipDepthBuffers& out);
  ZContact collide(const ViewCamera& cam, const SplatRenderer& splats, const Vec3d& tip);

 private:
  void ensureTarget(int w, int h);
  GLuint program_ = 0, fbo_ = 0, info_tex_ = 0, normal_tex_ = 0, depth_tex_ = 0;
  int w_ = 0, h_ = 0;
};

}  // namespace inc::viewer
