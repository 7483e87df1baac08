// GPU z-buffer tool collision: two depth-split passes over the splats into a small float target, read back.
#include "viewer/zbuffer_collision_gl.h"

#include <limits>
#include <stdexcept>
#include <vector>

namespace inc::viewer {

namespace {

// info = (view depth, facing +1/-1, 0, 1 = covered); normal = the splat's world normal.
const char* kFragment = R"(#version 330 core
in vec2 v_st;
in vec3 v_pos_view;
in vec3 v_normal_view;
in vec3 v_colour;
uniform mat4 u_view;
uniform float u_tip_depth;
uniform int u_side;
layout(location = 0) out vec4 out_info;
layout(location = 1) out vec4 out_normal;
void main() {
  if (dot(v_st, v_st) > 1.0) discard;
  float z = -v_pos_view.z;
  if (u_side == 0 ? (z >= u_tip_depth) : (z < u_tip_depth)) discard;
  out_info = vec4(z, gl_FrontFacing ? 1.0 : -1.0, 0.0, 1.0);
  out_normal = vec4(transpose(mat3(u_view)) * v_normal_view, 0.0);
}
)";

}  // namespace

ZBufferCollider::ZBufferCollider() {
  program_ = buildProgram(splatVertexSource(), kFragment, "z-buffer collision");
  glGenFramebuffers(1, &fbo_);
  checkGl("ZBufferCollider()");
}

ZBufferCollider::~ZBufferCollider() {
  glDeleteFramebuffers(1, &fbo_);
  glDeleteTextures(1, &info_tex_);
  glDeleteTextures(1, &normal_tex_);
  glDeleteTextures(1, &depth_tex_);
  glDeleteProgram(program_);
}

void ZBufferCollider::ensureTarget(int w, int h) {
  if (w == w_ && h == h_) return;
  auto make = [&](GLuint& tex, GLint internal, GLenum format) {
    if (!tex) glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, internal, w, h, 0, format, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  };
  make(info_tex_, GL_RGBA32F, GL_RGBA);
  make(normal_tex_, GL_RGBA32F, GL_RGBA);
  make(depth_tex_, GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, info_tex_, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, normal_tex_, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth_tex_, 0);
  const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glDrawBuffers(2, bufs);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("viewer: the z-buffer collision target (RGBA32F + depth) is incomplete");
  w_ = w;
  h_ = h;
}

void ZBufferCollider::render(const ViewCamera& cam, const SplatRenderer& splats, const Vec3d& tip,
                             TipDepthBuffers& out) {
  GLint prev_fbo = 0, prev_viewport[4];
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &prev_fbo);
  glGetIntegerv(GL_VIEWPORT, prev_viewport);
  ensureTarget(cam.width, cam.height);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, cam.width, cam.height);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glEnable(GL_DEPTH_TEST);
  glDepthMask(GL_TRUE);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);

  glUseProgram(program_);
  glUniformMatrix4fv(uniform(program_, "u_proj"), 1, GL_FALSE, cam.projectionMatrix().data());
  glUniformMatrix4fv(uniform(program_, "u_view"), 1, GL_FALSE, cam.viewMatrix().data());
  glUniform3f(uniform(program_, "u_eye"), float(cam.eye.x), float(cam.eye.y), float(cam.eye.z));
  glUniform3f(uniform(program_, "u_forward"), float(cam.forward.x), float(cam.forward.y), float(cam.forward.z));
  glUniform1i(uniform(program_, "u_ortho"), cam.orthographic ? 1 : 0);
  out.tip_depth = cam.viewDepth(tip);
  glUniform1f(uniform(program_, "u_tip_depth"), float(out.tip_depth));

  const std::size_t npix = std::size_t(cam.width) * cam.height;
  out.width = cam.width;
  out.height = cam.height;
  std::vector<float> info(npix * 4), normal(npix * 4);
  const float inf = std::numeric_limits<float>::infinity();
  for (int side = 0; side < 2; ++side) {
    const float zero[4] = {0, 0, 0, 0};
    glClearBufferfv(GL_COLOR, 0, zero);
    glClearBufferfv(GL_COLOR, 1, zero);
    const float clear_depth = side == 0 ? 0.0f : 1.0f;
    glClearBufferfv(GL_DEPTH, 0, &clear_depth);
    glDepthFunc(side == 0 ? GL_GREATER : GL_LESS);
    glUniform1i(uniform(program_, "u_side"), side);
    splats.drawInstances();
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, cam.width, cam.height, GL_RGBA, GL_FLOAT, info.data());
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, cam.width, cam.height, GL_RGBA, GL_FLOAT, normal.data());
    auto& depth = side == 0 ? out.before_depth : out.after_depth;
    auto& facing = side == 0 ? out.before_facing : out.after_facing;
    auto& nrm = side == 0 ? out.before_normal : out.after_normal;
    depth.assign(npix, side == 0 ? -inf : inf);
    facing.assign(npix, 0.0f);
    nrm.assign(npix * 3, 0.0f);
    for (std::size_t p = 0; p < npix; ++p) {
      if (info[4 * p + 3] <= 0.0f) continue;  // nothing on this side of the tip
      depth[p] = info[4 * p];
      facing[p] = info[4 * p + 1];
      for (int k = 0; k < 3; ++k) nrm[3 * p + k] = normal[4 * p + k];
    }
  }
  glDepthFunc(GL_LESS);
  glClearDepth(1.0);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glBindFramebuffer(GL_FRAMEBUFFER, GLuint(prev_fbo));
  glViewport(prev_viewport[0], prev_viewport[1], prev_viewport[2], prev_viewport[3]);
  checkGl("ZBufferCollider::render");
}

ZContact ZBufferCollider::collide(const ViewCamera& cam, const SplatRenderer& splats, const Vec3d& tip) {
  TipDepthBuffers buf;
  render(cam, splats, tip, buf);
  return readTipContact(cam, buf, tip);
}

}  // namespace inc::viewer
