// Ray-cast sphere impostors: an eye-facing quad per sphere, ray/sphere intersection and depth per fragment.
#include "viewer/sphere_renderer.h"

#include <cmath>

namespace inc::viewer {

namespace {

// Corners from gl_VertexID; the quad lies in the plane through the centre normal to the eye ray (perspective)
// or to the view axis (orthographic), half-size impostorHalfSize. Spheres containing the eye are dropped.
const char* kVertex = R"(#version 330 core
layout(location = 0) in vec3 a_center;
layout(location = 1) in float a_radius;
layout(location = 2) in float a_mark;
uniform mat4 u_proj, u_view;
uniform bool u_ortho, u_show_marks;
uniform vec3 u_colours[3];
out vec3 v_pos_view;
flat out vec3 v_center_view;
flat out float v_radius;
flat out vec3 v_colour;
void main() {
  vec3 c = (u_view * vec4(a_center, 1.0)).xyz;
  vec3 n = u_ortho ? vec3(0.0, 0.0, 1.0) : -normalize(c);
  float d = length(c);
  float s = u_ortho ? a_radius : (d > 1.0001 * a_radius ? a_radius * d / sqrt(d * d - a_radius * a_radius) : 0.0);
  vec3 a = abs(n.x) < 0.57 ? vec3(1, 0, 0) : (abs(n.y) < 0.57 ? vec3(0, 1, 0) : vec3(0, 0, 1));
  vec3 u = normalize(cross(n, a));
  vec3 v = cross(n, u);
  vec2 st = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
  vec3 p = c + s * (st.x * u + st.y * v);
  v_pos_view = p;
  v_center_view = c;
  v_radius = a_radius;
  v_colour = u_colours[u_show_marks ? clamp(int(a_mark + 0.5), 0, 2) : 0];
  gl_Position = s > 0.0 ? u_proj * vec4(p, 1.0) : vec4(2.0, 2.0, 2.0, 1.0);
}
)";

// The pixel's ray (from the eye through the fragment, or along -z in orthographic views) against the sphere:
// the nearest hit in front of the eye, its depth through the projection, headlight Phong at its normal.
const char* kFragment = R"(#version 330 core
in vec3 v_pos_view;
flat in vec3 v_center_view;
flat in float v_radius;
flat in vec3 v_colour;
uniform mat4 u_proj;
uniform bool u_ortho;
out vec4 frag;
void main() {
  vec3 o = u_ortho ? vec3(v_pos_view.xy, 0.0) : vec3(0.0);
  vec3 dir = u_ortho ? vec3(0.0, 0.0, -1.0) : normalize(v_pos_view);
  vec3 oc = o - v_center_view;
  float b = dot(oc, dir);
  float disc = b * b - (dot(oc, oc) - v_radius * v_radius);
  if (disc < 0.0) discard;
  float t = -b - sqrt(disc);
  if (t <= 0.0) discard;
  vec3 hit = o + t * dir;
  vec3 n = (hit - v_center_view) / v_radius;
  vec3 to_eye = -dir;
  float diffuse = max(dot(n, to_eye), 0.0);
  float spec = pow(max(dot(reflect(-to_eye, n), to_eye), 0.0), 24.0);
  frag = vec4(v_colour * (0.25 + 0.75 * diffuse) + vec3(0.25 * spec), 1.0);
  vec4 clip = u_proj * vec4(hit, 1.0);
  gl_FragDepth = clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0);
}
)";

}  // namespace

double impostorHalfSize(double radius_m, double distance_m, bool orthographic) {
  if (orthographic) return radius_m;
  if (!(distance_m > 1.0001 * radius_m)) return 0.0;
  return radius_m * distance_m / std::sqrt(distance_m * distance_m - radius_m * radius_m);
}

SphereRenderer::SphereRenderer() {
  program_ = buildProgram(kVertex, kFragment, "spheres");
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glEnableVertexAttribArray(0);
  const GLsizei stride = 5 * sizeof(float);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, nullptr);
  glVertexAttribDivisor(0, 1);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(3 * sizeof(float)));
  glVertexAttribDivisor(1, 1);
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(4 * sizeof(float)));
  glVertexAttribDivisor(2, 1);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  checkGl("SphereRenderer()");
}

SphereRenderer::~SphereRenderer() {
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
}

void SphereRenderer::upload(const std::vector<Vec3d>& centres, const std::vector<double>& radii,
                            const std::vector<std::uint8_t>& marks) {
  const std::size_t n = std::min(centres.size(), radii.size());
  std::vector<float> v(5 * n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) v[5 * i + std::size_t(k)] = float(centres[i][k]);
    v[5 * i + 3] = float(radii[i]);
    v[5 * i + 4] = i < marks.size() ? float(marks[i]) : 0.0f;
  }
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  count_ = n;
  checkGl("SphereRenderer::upload");
}

void SphereRenderer::draw(const ViewCamera& cam, const std::array<std::array<float, 3>, 3>& colours,
                          bool show_marks) const {
  if (count_ == 0) return;
  glUseProgram(program_);
  glUniformMatrix4fv(uniform(program_, "u_proj"), 1, GL_FALSE, cam.projectionMatrix().data());
  glUniformMatrix4fv(uniform(program_, "u_view"), 1, GL_FALSE, cam.viewMatrix().data());
  glUniform1i(uniform(program_, "u_ortho"), cam.orthographic ? 1 : 0);
  glUniform3fv(uniform(program_, "u_colours"), 3, colours[0].data());
  glUniform1i(uniform(program_, "u_show_marks"), show_marks ? 1 : 0);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glBindVertexArray(vao_);
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(count_));
  glBindVertexArray(0);
  checkGl("SphereRenderer::draw");
}

}  // namespace inc::viewer
