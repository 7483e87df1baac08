// An RGBA8 + 24-bit depth framebuffer object: renders of a fixed size independent of the window (tests, captures).
#pragma once

#include "viewer/gl_api.h"

namespace inc::viewer {

class OffscreenTarget {
 public:
  OffscreenTarget(int width, int height);  // needs a current GL context; throws when incomplete
  ~OffscreenTarget();
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;
  // Binds it for drawing and reading, sets the viewport.
  void bind() const;
  static void bindDefault(int width, int height);
  int width() const { return w_; }
  int height() const { return h_; }

 private:
  int w_, h_;
  GLuint fbo_ = 0, colour_ = 0, depth_ = 0;
};

}  // namespace inc::viewer
