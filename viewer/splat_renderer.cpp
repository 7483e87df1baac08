// GPU point splatting: instanced disc sprites, visibility + accumulation passes into a float target, resolve.
#include "viewer/splat_renderer.h"

#include <stdexcept>
#include <vector>

namespace inc::viewer {

namespace {

// One instance per splat; corners from gl_VertexID. The quad lies in the disc's plane, so the interpolated
// (perspective-correct) view position of a fragment is exactly the pixel ray's hit on the disc plane and
// the rasterised depth is the disc's true depth there.
const char* kSplatVertex = R"(#version 330 core
layout(location = 0) in vec3 a_center;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in float a_radius;
layout(location = 3) in vec3 a_colour;
uniform mat4 u_proj, u_view;
uniform vec3 u_eye, u_forward;
uniform bool u_ortho;
out vec2 v_st;
out vec3 v_pos_view;
out vec3 v_normal_view;
out vec3 v_colour;
vec3 anyPerpendicular(vec3 n) {
  vec3 a = abs(n.x) < 0.57 ? vec3(1, 0, 0) : (abs(n.y) < 0.57 ? vec3(0, 1, 0) : vec3(0, 0, 1));
  return normalize(cross(n, a));
}
void main() {
  vec3 n = a_normal;
  if (dot(n, n) <= 0.25) n = u_ortho ? -u_forward : normalize(u_eye - a_center);  // no normal: face the eye
  vec3 u = anyPerpendicular(n);
  vec3 v = cross(n, u);
  vec2 st = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0);
  vec3 p = a_center + a_radius * (st.x * u + st.y * v);
  vec4 pv = u_view * vec4(p, 1.0);
  v_st = st;
  v_pos_view = pv.xyz;
  v_normal_view = mat3(u_view) * n;
  v_colour = a_colour;
  gl_Position = u_proj * pv;
}
)";

// u_pass 0: visibility, depth pushed back by epsilon (view metres). u_pass 1: accumulation of weights.
const char* kSplatFragment = R"(#version 330 core
in vec2 v_st;
in vec3 v_pos_view;
in vec3 v_normal_view;
in vec3 v_colour;
uniform mat4 u_proj;
uniform int u_pass;
uniform float u_eps, u_sigma_fraction;
layout(location = 0) out vec4 out_accum;
layout(location = 1) out vec4 out_normal;
void main() {
  float rho2 = dot(v_st, v_st);  // (rho / r)^2
  if (rho2 > 1.0) discard;
  if (u_pass == 0) {
    vec4 clip = u_proj * vec4(v_pos_view + vec3(0.0, 0.0, -u_eps), 1.0);
    gl_FragDepth = clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0);
    out_accum = vec4(0.0);
    out_normal = vec4(0.0);
    return;
  }
  float w = exp(-rho2 / (2.0 * u_sigma_fraction * u_sigma_fraction));
  vec3 n = gl_FrontFacing ? v_normal_view : -v_normal_view;
  out_accum = vec4(v_colour * w, w);
  out_normal = vec4(n * w, -v_pos_view.z * w);
  gl_FragDepth = gl_FragCoord.z;
}
)";

const char* kResolveVertex = R"(#version 330 core
out vec2 v_uv;
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  v_uv = 0.5 * p + 0.5;
  gl_Position = vec4(p, 0.0, 1.0);
}
)";

// Normalises the sums, lights the blended normal with a headlight, and writes the blended depth.
const char* kResolveFragment = R"(#version 330 core
in vec2 v_uv;
uniform sampler2D u_accum, u_normal;
uniform mat4 u_proj;
out vec4 frag;
void main() {
  vec4 a = texture(u_accum, v_uv);
  if (a.w <= 0.0) discard;
  vec4 nz = texture(u_normal, v_uv);
  vec3 colour = a.rgb / a.w;
  float z = nz.w / a.w;  // blended view depth, m
  vec3 n = normalize(nz.xyz);
  // Headlight: the direction to the eye is close to +z in view space over a narrow field of view.
  float diffuse = max(n.z, 0.0);
  float spec = pow(max(2.0 * n.z * n.z - 1.0, 0.0), 24.0);
  frag = vec4(colour * (0.25 + 0.75 * diffuse) + vec3(0.2 * spec), 1.0);
  vec4 clip = u_proj * vec4(0.0, 0.0, -z, 1.0);
  gl_FragDepth = clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0);
}
)";

}  // namespace

const char* splatVertexSource() { return kSplatVertex; }

void SplatRenderer::drawInstances() const {
  if (count_ == 0) return;
  glBindVertexArray(vao_);
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(count_));
  glBindVertexArray(0);
}

SplatRenderer::SplatRenderer() {
  splat_program_ = buildProgram(kSplatVertex, kSplatFragment, "splat");
  resolve_program_ = buildProgram(kResolveVertex, kResolveFragment, "splat resolve");
  glGenVertexArrays(1, &vao_);
  glGenVertexArrays(1, &empty_vao_);
  glGenBuffers(1, &instance_vbo_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, instance_vbo_);
  const GLsizei stride = 10 * sizeof(float);
  const int sizes[4] = {3, 3, 1, 3};
  std::size_t offset = 0;
  for (GLuint k = 0; k < 4; ++k) {
    glEnableVertexAttribArray(k);
    glVertexAttribPointer(k, sizes[k], GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offset * sizeof(float)));
    glVertexAttribDivisor(k, 1);
    offset += std::size_t(sizes[k]);
  }
  glBindVertexArray(0);
  glGenFramebuffers(1, &fbo_);
  checkGl("SplatRenderer()");
}

SplatRenderer::~SplatRenderer() {
  glDeleteFramebuffers(1, &fbo_);
  glDeleteTextures(1, &accum_tex_);
  glDeleteTextures(1, &normal_tex_);
  glDeleteTextures(1, &depth_tex_);
  glDeleteBuffers(1, &instance_vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteVertexArrays(1, &empty_vao_);
  glDeleteProgram(splat_program_);
  glDeleteProgram(resolve_program_);
}

void SplatRenderer::upload(const SplatCloud& cloud) {
  std::vector<float> v(cloud.size() * 10);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    float* o = &v[10 * i];
    const Vec3d n = i < cloud.normals.size() ? cloud.normals[i] : Vec3d{0, 0, 0};
    for (int k = 0; k < 3; ++k) {
      o[k] = float(cloud.centers[i][k]);
      o[3 + k] = float(n[k]);
      o[7 + k] = cloud.colours.empty() ? 1.0f : cloud.colours[i][std::size_t(k)];
    }
    o[6] = float(cloud.radii[i]);
  }
  glBindBuffer(GL_ARRAY_BUFFER, instance_vbo_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  count_ = cloud.size();
  checkGl("SplatRenderer::upload");
}

void SplatRenderer::ensureTargets(int w, int h) {
  if (w == target_w_ && h == target_h_) return;
  auto make = [&](GLuint& tex, GLint internal, GLenum format, GLenum type) {
    if (!tex) glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, internal, w, h, 0, format, type, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  };
  make(accum_tex_, GL_RGBA32F, GL_RGBA, GL_FLOAT);
  make(normal_tex_, GL_RGBA32F, GL_RGBA, GL_FLOAT);
  make(depth_tex_, GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT, GL_FLOAT);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, accum_tex_, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, normal_tex_, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth_tex_, 0);
  const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glDrawBuffers(2, bufs);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("viewer: the splat render target (RGBA32F + depth) is incomplete on this driver");
  target_w_ = w;
  target_h_ = h;
  checkGl("SplatRenderer::ensureTargets");
}

void SplatRenderer::draw(const ViewCamera& cam, const SplatParams& params) {
  if (count_ == 0) return;
  GLint prev_fbo = 0, prev_viewport[4];
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &prev_fbo);
  glGetIntegerv(GL_VIEWPORT, prev_viewport);
  ensureTargets(cam.width, cam.height);

  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, cam.width, cam.height);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glEnable(GL_DEPTH_TEST);
  glDepthMask(GL_TRUE);
  glClearColor(0, 0, 0, 0);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

  glUseProgram(splat_program_);
  glUniformMatrix4fv(uniform(splat_program_, "u_proj"), 1, GL_FALSE, cam.projectionMatrix().data());
  glUniformMatrix4fv(uniform(splat_program_, "u_view"), 1, GL_FALSE, cam.viewMatrix().data());
  glUniform3f(uniform(splat_program_, "u_eye"), float(cam.eye.x), float(cam.eye.y), float(cam.eye.z));
  glUniform3f(uniform(splat_program_, "u_forward"), float(cam.forward.x), float(cam.forward.y), float(cam.forward.z));
  glUniform1i(uniform(splat_program_, "u_ortho"), cam.orthographic ? 1 : 0);
  glUniform1f(uniform(splat_program_, "u_eps"), float(params.depth_epsilon_m));
  glUniform1f(uniform(splat_program_, "u_sigma_fraction"), float(params.sigma_fraction));
  glBindVertexArray(vao_);

  // Pass 1: visibility (nearest disc depth + epsilon), no colour.
  glUniform1i(uniform(splat_program_, "u_pass"), 0);
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glDepthFunc(GL_LESS);
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(count_));

  // Pass 2: every disc at most epsilon behind the visible one adds its Gaussian weight (additive, order-free).
  glUniform1i(uniform(splat_program_, "u_pass"), 1);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_FALSE);
  glDepthFunc(GL_LEQUAL);
  glEnable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFunc(GL_ONE, GL_ONE);
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(count_));
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);

  // Pass 3: normalise into the caller's framebuffer, depth-tested against what is already drawn there.
  glBindFramebuffer(GL_FRAMEBUFFER, GLuint(prev_fbo));
  glViewport(prev_viewport[0], prev_viewport[1], prev_viewport[2], prev_viewport[3]);
  glUseProgram(resolve_program_);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, accum_tex_);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, normal_tex_);
  glActiveTexture(GL_TEXTURE0);
  glUniform1i(uniform(resolve_program_, "u_accum"), 0);
  glUniform1i(uniform(resolve_program_, "u_normal"), 1);
  glUniformMatrix4fv(uniform(resolve_program_, "u_proj"), 1, GL_FALSE, cam.projectionMatrix().data());
  glDepthFunc(GL_LESS);
  glBindVertexArray(empty_vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  checkGl("SplatRenderer::draw");
}

}  // namespace inc::viewer
