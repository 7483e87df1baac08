// Flat-colour triangle overlays (translucent swept surface, arrows drawn on top) and the arrow geometry.
#include "viewer/overlay_renderer.h"

#include <algorithm>
#include <cmath>

namespace inc::viewer {

namespace {

const char* kVertex = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
uniform mat4 u_proj, u_view;
void main() { gl_Position = u_proj * u_view * vec4(a_pos, 1.0); }
)";

const char* kFragment = R"(#version 330 core
uniform vec4 u_rgba;
out vec4 frag;
void main() { frag = u_rgba; }
)";

}  // namespace

double pixelSizeAt(const ViewCamera& cam, const Vec3d& p) {
  const double span =
      cam.orthographic ? 2.0 * cam.half_height : 2.0 * cam.half_height * std::max(cam.viewDepth(p), cam.near_m);
  return span / double(cam.height);
}

void arrowTriangles(const ViewCamera& cam, const Vec3d& origin, const Vec3d& tip, double width_m,
                    std::vector<Vec3d>& out) {
  const Vec3d d = tip - origin;
  const double len = norm(d);
  if (!(len > 0) || !(width_m > 0)) return;
  const Vec3d axis = d * (1.0 / len);
  // The side direction: normal to the arrow and to the line of sight at its middle (the ribbon faces the eye).
  const Vec3d sight = cam.orthographic ? cam.forward : (origin + tip) * 0.5 - cam.eye;
  const Vec3d side_raw = cross(axis, sight);
  const double s = norm(side_raw);
  if (!(s > 1e-9 * norm(sight))) return;  // pointing at the eye: nothing to draw
  const Vec3d side = side_raw * (1.0 / s);
  const double head = std::min(0.35 * len, 4.0 * width_m);
  const Vec3d base = tip - axis * head;
  const Vec3d w = side * (0.5 * width_m), W = side * (1.5 * width_m);
  const Vec3d quad[4] = {origin - w, origin + w, base + w, base - w};
  out.insert(out.end(), {quad[0], quad[1], quad[2], quad[0], quad[2], quad[3]});
  out.insert(out.end(), {base - W, base + W, tip});
}

OverlayRenderer::OverlayRenderer() {
  program_ = buildProgram(kVertex, kFragment, "overlay");
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  checkGl("OverlayRenderer()");
}

OverlayRenderer::~OverlayRenderer() {
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
}

void OverlayRenderer::draw(const ViewCamera& cam, const TriangleMesh& mesh, const OverlayStyle& style) {
  std::vector<Vec3d> v;
  v.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) v.push_back(mesh.vertices[std::size_t(t[std::size_t(k)])]);
  draw(cam, v, style);
}

void OverlayRenderer::draw(const ViewCamera& cam, const std::vector<Vec3d>& tv, const OverlayStyle& style) {
  if (tv.empty()) return;
  std::vector<float> f(tv.size() * 3);
  for (std::size_t i = 0; i < tv.size(); ++i)
    for (int k = 0; k < 3; ++k) f[3 * i + std::size_t(k)] = float(tv[i][k]);
  glUseProgram(program_);
  glUniformMatrix4fv(uniform(program_, "u_proj"), 1, GL_FALSE, cam.projectionMatrix().data());
  glUniformMatrix4fv(uniform(program_, "u_view"), 1, GL_FALSE, cam.viewMatrix().data());
  glUniform4fv(uniform(program_, "u_rgba"), 1, style.rgba.data());
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(f.size() * sizeof(float)), f.data(), GL_STREAM_DRAW);
  const bool blend = style.rgba[3] < 1.0f;
  if (style.depth_test) {
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
  } else {
    glDisable(GL_DEPTH_TEST);
  }
  glDepthMask(blend || !style.depth_test ? GL_FALSE : GL_TRUE);  // translucent and on-top layers leave the depth
  glDisable(GL_CULL_FACE);
  if (blend) {
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  }
  glDrawArrays(GL_TRIANGLES, 0, GLsizei(tv.size()));
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);
  glEnable(GL_DEPTH_TEST);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  checkGl("OverlayRenderer::draw");
}

}  // namespace inc::viewer
