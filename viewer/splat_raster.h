// Point splatting (MFS Heller-myotomy paper, section 3) on the CPU: oriented Gaussian discs, depth-correct blending.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "physics/vec3.h"
#include "viewer/view_camera.h"

namespace inc::viewer {

// Structure of arrays, one splat per point. A zero normal means "no orientation known": the disc then
// faces the viewer (and counts as front facing in the z-buffer collision).
struct SplatCloud {
  std::vector<Vec3d> centers;                 // m
  std::vector<Vec3d> normals;                 // unit outward normals, or zero
  std::vector<double> radii;                  // m, disc radius (the Gaussian is cut off there)
  std::vector<std::array<float, 3>> colours;  // linear RGB in [0, 1]; empty: all white
  std::size_t size() const { return centers.size(); }
};

struct SplatParams {
  // Footprint: w(rho) = exp(-rho^2 / (2 sigma^2)) with sigma = sigma_fraction * radius, cut off at rho = radius.
  double sigma_fraction = 0.5;
  // Depth window of the blend, m: a splat joins the blend at a pixel if its depth there is within
  // depth_epsilon_m of the nearest splat's depth (the visibility pass is shifted back by this much).
  double depth_epsilon_m = 1e-3;
};

// The result of splatting: per pixel (row-major, row 0 at the bottom) the nearest depth, and the
// Gaussian-weighted blend of every splat within the depth window of it.
struct SplatImage {
  int width = 0, height = 0;
  std::vector<float> nearest_depth;  // view depth of the visible surface, m; +inf where nothing was hit
  std::vector<float> blended_depth;  // sum(w z) / sum(w), m; +inf where nothing was hit
  std::vector<float> weight;         // sum(w); 0 where nothing was hit
  std::vector<float> rgb;            // 3 per pixel: sum(w c) / sum(w)
  std::vector<float> normal;         // 3 per pixel: normalised sum(w n), n turned towards the viewer
  bool covered(int x, int y) const { return weight[std::size_t(y) * width + x] > 0.0f; }
};

// Ray/disc intersection, the depth-correct part of splatting: the ray o + t d meets the plane of the
// disc (centre c, unit normal n) at t; rho2 is the squared distance of that point from c.
// Returns false when the ray is parallel to the plane or the hit is behind the origin.
bool intersectSplatPlane(const Vec3d& o, const Vec3d& d, const Vec3d& c, const Vec3d& n, double& t, double& rho2);

// The normal a splat actually uses for a view: its own, or facing the eye when it has none.
Vec3d splatNormalForView(const ViewCamera& cam, const Vec3d& center, const Vec3d& normal);

// Screen-space bounding box of a disc (inclusive pixel range); false when it lies off screen or straddles
// the eye plane (such a splat is skipped: the renderer's near plane clips it too).
bool splatPixelBounds(const ViewCamera& cam, const Vec3d& c, const Vec3d& n, double radius, int& x0, int& y0, int& x1,
                      int& y1);

// Two passes as on the GPU: visibility (nearest depth), then accumulation of every splat within
// depth_epsilon_m of it. O(total footprint area); parallel over rows.
void rasterizeSplats(const ViewCamera& cam, const SplatCloud& cloud, const SplatParams& params, SplatImage& out);

}  // namespace inc::viewer
