// The OpenGL 3.3 core API for the viewer: prototypes from glcorearb.h, resolved by libOpenGL (GLVND).
#pragma once

#ifndef GLFW_INCLUDE_NONE
#define GLFW_INCLUDE_NONE
#endif
#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>

#include <string>

namespace inc::viewer {

// Compiles and links a vertex + fragment program; throws std::runtime_error with the driver's log.
GLuint buildProgram(const char* vertex_src, const char* fragment_src, const std::string& name);
GLint uniform(GLuint program, const char* name);
// Throws std::runtime_error naming `where` when glGetError reports an error.
void checkGl(const char* where);

}  // namespace inc::viewer
