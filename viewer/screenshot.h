// Reading back the framebuffer and writing it as PNG (stb_image_write).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace inc::viewer {

struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // 3 bytes per pixel, row 0 at the BOTTOM (as glReadPixels returns it)
  const std::uint8_t* at(int x, int y) const { return &rgb[3 * (std::size_t(y) * width + x)]; }
};

// Reads the currently bound read framebuffer (e.g. the back buffer before the swap).
RgbImage readFramebuffer(int width, int height);
// Reads window depth values in [0, 1], row 0 at the bottom.
std::vector<float> readDepth(int x, int y, int width, int height);
// Writes the image top row first; throws std::runtime_error when the file cannot be written.
void writePng(const std::string& path, const RgbImage& img);

}  // namespace inc::viewer
