// Framebuffer read-back (colour and depth) and PNG output through stb_image_write (libstb).
#include "viewer/screenshot.h"

#include <algorithm>
#include <stdexcept>

#include <stb_image_write.h>

#include "viewer/gl_api.h"

namespace inc::viewer {

RgbImage readFramebuffer(int width, int height) {
  RgbImage img;
  img.width = width;
  img.height = height;
  img.rgb.assign(std::size_t(width) * height * 3, 0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, img.rgb.data());
  checkGl("readFramebuffer");
  return img;
}

std::vector<float> readDepth(int x, int y, int width, int height) {
  std::vector<float> d(std::size_t(width) * height, 1.0f);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(x, y, width, height, GL_DEPTH_COMPONENT, GL_FLOAT, d.data());
  checkGl("readDepth");
  return d;
}

void writePng(const std::string& path, const RgbImage& img) {
  if (img.width <= 0 || img.height <= 0) throw std::runtime_error("viewer: empty image, nothing to write to " + path);
  // PNG rows go top first; GL rows bottom first.
  const std::size_t stride = std::size_t(img.width) * 3;
  std::vector<std::uint8_t> flipped(img.rgb.size());
  for (int y = 0; y < img.height; ++y)
    std::copy_n(img.rgb.data() + std::size_t(img.height - 1 - y) * stride, stride, flipped.data() + y * stride);
  if (!stbi_write_png(path.c_str(), img.width, img.height, 3, flipped.data(), int(stride)))
    throw std::runtime_error("viewer: cannot write PNG " + path);
}

}  // namespace inc::viewer
