// Shader compilation and GL error checks for the viewer's renderers.
#include "viewer/gl_api.h"

#include <stdexcept>
#include <vector>

namespace inc::viewer {

namespace {

GLuint compileStage(GLenum kind, const char* src, const std::string& name) {
  const GLuint s = glCreateShader(kind);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
    std::vector<char> log(std::size_t(len) + 1, '\0');
    glGetShaderInfoLog(s, len, nullptr, log.data());
    glDeleteShader(s);
    throw std::runtime_error("viewer: shader '" + name + "' (" + (kind == GL_VERTEX_SHADER ? "vertex" : "fragment") +
                             ") failed to compile: " + log.data());
  }
  return s;
}

}  // namespace

GLuint buildProgram(const char* vertex_src, const char* fragment_src, const std::string& name) {
  const GLuint vs = compileStage(GL_VERTEX_SHADER, vertex_src, name);
  const GLuint fs = compileStage(GL_FRAGMENT_SHADER, fragment_src, name);
  const GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetProgramiv(p, GL_INFO_LOG_LENGTH, &len);
    std::vector<char> log(std::size_t(len) + 1, '\0');
    glGetProgramInfoLog(p, len, nullptr, log.data());
    glDeleteProgram(p);
    throw std::runtime_error("viewer: program '" + name + "' failed to link: " + log.data());
  }
  return p;
}

GLint uniform(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

void checkGl(const char* where) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR)
    throw std::runtime_error(std::string("viewer: OpenGL error 0x") + std::to_string(e) + " in " + where);
}

}  // namespace inc::viewer
