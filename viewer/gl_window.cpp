// GLFW start-up (once per process, ref-counted) and window creation with a 3.3 core profile context.
#include "viewer/gl_window.h"

#include "viewer/gl_api.h"

#include <GLFW/glfw3.h>

#include <chrono>
#include <cstdlib>
#include <mutex>
#include <thread>

namespace inc::viewer {

namespace {

std::mutex g_glfw_mutex;
int g_glfw_users = 0;
std::string g_last_error;

void onGlfwError(int code, const char* text) { g_last_error = "GLFW error " + std::to_string(code) + ": " + text; }

}  // namespace

std::unique_ptr<GlWindow> GlWindow::open(const GlWindowOptions& opt, std::string* why) {
  std::lock_guard<std::mutex> lock(g_glfw_mutex);
  glfwSetErrorCallback(onGlfwError);
  // An X server that resets when its last client leaves (Xvfb without -noreset, as xvfb-run starts it)
  // refuses connections for a moment after a previous window closed: retry briefly before giving up.
  bool ok = g_glfw_users > 0;
  const char* display = std::getenv("DISPLAY");
  const int attempts = (display && *display) ? 5 : 1;  // no DISPLAY at all: nothing to wait for
  for (int attempt = 0; !ok && attempt < attempts; ++attempt) {
    if (attempt > 0) std::this_thread::sleep_for(std::chrono::milliseconds(50 << attempt));
    ok = glfwInit() == GLFW_TRUE;
  }
  if (!ok) {
    if (why) *why = "no display could be opened (" + g_last_error + ")";
    return nullptr;
  }
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_VISIBLE, opt.visible ? GLFW_TRUE : GLFW_FALSE);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);
  GLFWwindow* w = glfwCreateWindow(opt.width, opt.height, opt.title.c_str(), nullptr, nullptr);
  if (!w) {
    if (why) *why = "no OpenGL 3.3 core window could be created (" + g_last_error + ")";
    if (g_glfw_users == 0) glfwTerminate();
    return nullptr;
  }
  ++g_glfw_users;
  glfwMakeContextCurrent(w);
  glfwSwapInterval(opt.vsync ? 1 : 0);
  return std::unique_ptr<GlWindow>(new GlWindow(w));
}

GlWindow::~GlWindow() {
  std::lock_guard<std::mutex> lock(g_glfw_mutex);
  glfwDestroyWindow(window_);
  if (--g_glfw_users == 0) glfwTerminate();
}

void GlWindow::framebufferSize(int& w, int& h) const { glfwGetFramebufferSize(window_, &w, &h); }

std::string GlWindow::glVersion() const {
  const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return std::string(v ? v : "?") + " / " + (r ? r : "?");
}

}  // namespace inc::viewer
