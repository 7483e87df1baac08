// Surface mesh upload (positions + area-weighted normals) and a headlight Phong shader.
#include "viewer/surface_renderer.h"

#include <cmath>

namespace inc::viewer {

namespace {

const char* kVertex = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_proj, u_view, u_model;
out vec3 v_pos_view;
out vec3 v_normal_view;
void main() {
  vec4 pv = u_view * u_model * vec4(a_pos, 1.0);
  v_pos_view = pv.xyz;
  v_normal_view = mat3(u_view * u_model) * a_normal;  // rigid model/view: no inverse transpose needed
  gl_Position = u_proj * pv;
}
)";

// Headlight Phong; the back side of a triangle (seen through a cut or a hole) gets the cut-wall colour.
const char* kFragment = R"(#version 330 core
in vec3 v_pos_view;
in vec3 v_normal_view;
uniform vec3 u_front, u_back;
uniform float u_specular, u_shininess;
out vec4 frag;
void main() {
  vec3 n = normalize(v_normal_view);
  if (!gl_FrontFacing) n = -n;
  vec3 to_eye = normalize(-v_pos_view);
  vec3 base = gl_FrontFacing ? u_front : u_back;
  float diffuse = max(dot(n, to_eye), 0.0);
  float spec = pow(max(dot(reflect(-to_eye, n), to_eye), 0.0), u_shininess);
  vec3 c = base * (0.25 + 0.75 * diffuse) + vec3(u_specular * spec);
  frag = vec4(c, 1.0);
}
)";

}  // namespace

std::vector<Vec3d> vertexNormals(const TriangleMesh& mesh) {
  std::vector<Vec3d> n(mesh.vertices.size(), Vec3d{0, 0, 0});
  for (const auto& t : mesh.triangles) {
    const Vec3d a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    const Vec3d area2 = cross(b - a, c - a);  // |.| = twice the area: area weighting
    for (int k = 0; k < 3; ++k) n[t[k]] = n[t[k]] + area2;
  }
  for (auto& v : n) v = normalizeOr(v, Vec3d{0, 0, 0});
  return n;
}

SurfaceRenderer::SurfaceRenderer() {
  program_ = buildProgram(kVertex, kFragment, "surface");
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glGenBuffers(1, &ebo_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<void*>(3 * sizeof(float)));
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo_);
  glBindVertexArray(0);
  checkGl("SurfaceRenderer()");
}

SurfaceRenderer::~SurfaceRenderer() {
  glDeleteBuffers(1, &ebo_);
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
}

void SurfaceRenderer::upload(const TriangleMesh& mesh, const std::vector<std::uint8_t>& cut_walls) {
  const std::vector<Vec3d> normals = vertexNormals(mesh);
  std::vector<float> v(mesh.vertices.size() * 6);
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      v[6 * i + k] = float(mesh.vertices[i][k]);
      v[6 * i + 3 + k] = float(normals[i][k]);
    }
  std::vector<GLuint> idx, walls;
  idx.reserve(mesh.triangles.size() * 3);
  const bool flagged = cut_walls.size() == mesh.triangles.size();
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) (flagged && cut_walls[f] ? walls : idx).push_back(GLuint(mesh.triangles[f][k]));
  wall_index_count_ = GLsizei(walls.size());
  idx.insert(idx.end(), walls.begin(), walls.end());
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_DYNAMIC_DRAW);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(idx.size() * sizeof(GLuint)), idx.data(), GL_DYNAMIC_DRAW);
  glBindVertexArray(0);
  index_count_ = GLsizei(idx.size());
  checkGl("SurfaceRenderer::upload");
}

void SurfaceRenderer::draw(const ViewCamera& cam, const SurfaceStyle& style, const Mat4f& model) const {
  if (index_count_ == 0) return;
  glUseProgram(program_);
  glUniformMatrix4fv(uniform(program_, "u_proj"), 1, GL_FALSE, cam.projectionMatrix().data());
  glUniformMatrix4fv(uniform(program_, "u_view"), 1, GL_FALSE, cam.viewMatrix().data());
  glUniformMatrix4fv(uniform(program_, "u_model"), 1, GL_FALSE, model.data());
  glUniform3fv(uniform(program_, "u_front"), 1, style.front.data());
  glUniform3fv(uniform(program_, "u_back"), 1, style.back.data());
  glUniform1f(uniform(program_, "u_specular"), style.specular);
  glUniform1f(uniform(program_, "u_shininess"), style.shininess);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(style.on_top ? GL_ALWAYS : GL_LESS);
  glDisable(GL_CULL_FACE);
  glPolygonMode(GL_FRONT_AND_BACK, style.wireframe ? GL_LINE : GL_FILL);
  glBindVertexArray(vao_);
  const GLsizei tissue = index_count_ - wall_index_count_;
  if (tissue > 0) glDrawElements(GL_TRIANGLES, tissue, GL_UNSIGNED_INT, nullptr);
  if (wall_index_count_ > 0) {  // cut walls: the cut-wall colour on both sides
    glUniform3fv(uniform(program_, "u_front"), 1, style.back.data());
    glDrawElements(GL_TRIANGLES, wall_index_count_, GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(std::size_t(tissue) * sizeof(GLuint)));
  }
  glBindVertexArray(0);
  glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  glDepthFunc(GL_LESS);
  checkGl("SurfaceRenderer::draw");
}

}  // namespace inc::viewer
