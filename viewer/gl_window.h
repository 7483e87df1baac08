// A GLFW window with an OpenGL 3.3 core context; reports clearly when no display can be opened.
#pragma once

#include <memory>
#include <string>

struct GLFWwindow;

namespace inc::viewer {

struct GlWindowOptions {
  int width = 1280;  // screen coordinates
  int height = 800;
  bool visible = true;
  bool vsync = true;
  std::string title = "Incision";
};

class GlWindow {
 public:
  // nullptr when GLFW cannot start (no display) or no 3.3 core context exists; `why` says which.
  static std::unique_ptr<GlWindow> open(const GlWindowOptions& opt, std::string* why);
  ~GlWindow();
  GlWindow(const GlWindow&) = delete;
  GlWindow& operator=(const GlWindow&) = delete;

  GLFWwindow* handle() const { return window_; }
  void framebufferSize(int& w, int& h) const;
  std::string glVersion() const;  // "4.5 (Core Profile) Mesa ..." and the renderer name

 private:
  explicit GlWindow(GLFWwindow* w) : window_(w) {}
  GLFWwindow* window_ = nullptr;
};

}  // namespace inc::viewer
