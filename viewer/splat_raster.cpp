// CPU point splatting: per-pixel ray/disc intersection, nearest-depth visibility and Gaussian blending.
#include "viewer/splat_raster.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/parallel.h"

namespace inc::viewer {

bool intersectSplatPlane(const Vec3d& o, const Vec3d& d, const Vec3d& c, const Vec3d& n, double& t, double& rho2) {
  const double dn = dot(d, n);
  if (std::fabs(dn) < 1e-12) return false;
  t = dot(c - o, n) / dn;
  if (!(t > 0.0)) return false;
  const Vec3d p = o + d * t;
  rho2 = norm2(p - c);
  return true;
}

Vec3d splatNormalForView(const ViewCamera& cam, const Vec3d& center, const Vec3d& normal) {
  if (norm2(normal) > 0.25) return normal;  // a real (unit) normal
  return cam.orthographic ? -cam.forward : normalizeOr(cam.eye - center, -cam.forward);
}

bool splatPixelBounds(const ViewCamera& cam, const Vec3d& c, const Vec3d& n, double radius, int& x0, int& y0, int& x1,
                      int& y1) {
  // The disc lies inside the square c +- r u +- r v of its plane; a convex quad in front of the eye projects
  // to a convex region holding the disc's projection, so the corners' pixel box bounds the footprint.
  const Vec3d u = anyPerpendicular(n);
  const Vec3d v = cross(n, u);
  double lo_x = std::numeric_limits<double>::infinity(), lo_y = lo_x, hi_x = -lo_x, hi_y = -lo_x;
  for (int k = 0; k < 4; ++k) {
    const Vec3d p = c + u * (radius * ((k & 1) ? 1.0 : -1.0)) + v * (radius * ((k & 2) ? 1.0 : -1.0));
    double px, py, depth;
    if (!cam.project(p, px, py, depth)) return false;
    if (!cam.orthographic && depth < cam.near_m) return false;
    lo_x = std::min(lo_x, px);
    hi_x = std::max(hi_x, px);
    lo_y = std::min(lo_y, py);
    hi_y = std::max(hi_y, py);
  }
  // Pixel centres at i + 0.5: the covered centres are those in [lo, hi].
  x0 = std::max(0, int(std::ceil(lo_x - 0.5)));
  y0 = std::max(0, int(std::ceil(lo_y - 0.5)));
  x1 = std::min(cam.width - 1, int(std::floor(hi_x - 0.5)));
  y1 = std::min(cam.height - 1, int(std::floor(hi_y - 0.5)));
  return x0 <= x1 && y0 <= y1;
}

namespace {

struct Box {
  int x0, y0, x1, y1;
};

constexpr int kBandRows = 8;

}  // namespace

void rasterizeSplats(const ViewCamera& cam, const SplatCloud& cloud, const SplatParams& params, SplatImage& out) {
  const int w = cam.width, h = cam.height;
  const std::size_t npix = std::size_t(w) * h;
  const float inf = std::numeric_limits<float>::infinity();
  out.width = w;
  out.height = h;
  out.nearest_depth.assign(npix, inf);
  out.blended_depth.assign(npix, inf);
  out.weight.assign(npix, 0.0f);
  out.rgb.assign(npix * 3, 0.0f);
  out.normal.assign(npix * 3, 0.0f);

  const std::size_t n = cloud.size();
  std::vector<Vec3d> normals(n);
  std::vector<Box> boxes(n);
  std::vector<char> on_screen(n, 0);
  cpu::parallelFor(std::int64_t(n), [&](std::int64_t i) {
    normals[i] =
        splatNormalForView(cam, cloud.centers[i], i < std::int64_t(cloud.normals.size()) ? cloud.normals[i] : Vec3d{});
    Box& b = boxes[i];
    on_screen[i] = splatPixelBounds(cam, cloud.centers[i], normals[i], cloud.radii[i], b.x0, b.y0, b.x1, b.y1) ? 1 : 0;
  });

  // Bin splats by bands of rows so each band is written by one thread only (gather, no races).
  const int nbands = (h + kBandRows - 1) / kBandRows;
  std::vector<std::vector<std::int32_t>> bands(static_cast<std::size_t>(nbands));
  for (std::size_t i = 0; i < n; ++i) {
    if (!on_screen[i]) continue;
    for (int b = boxes[i].y0 / kBandRows; b <= boxes[i].y1 / kBandRows; ++b) bands[b].push_back(std::int32_t(i));
  }

  const double eps = params.depth_epsilon_m;
  cpu::parallelFor(nbands, [&](std::int64_t band) {
    const int row0 = int(band) * kBandRows, row1 = std::min(h, row0 + kBandRows);
    // Pass 1: visibility, the nearest disc along each pixel's ray.
    for (std::int32_t i : bands[band]) {
      const Box& b = boxes[i];
      const double r2 = cloud.radii[i] * cloud.radii[i];
      for (int y = std::max(row0, b.y0); y <= std::min(row1 - 1, b.y1); ++y)
        for (int x = b.x0; x <= b.x1; ++x) {
          Vec3d o, d;
          cam.pixelRay(x + 0.5, y + 0.5, o, d);
          double t, rho2;
          if (!intersectSplatPlane(o, d, cloud.centers[i], normals[i], t, rho2) || rho2 > r2) continue;
          const double z = t * dot(d, cam.forward);
          float& nz = out.nearest_depth[std::size_t(y) * w + x];
          if (z < nz) nz = float(z);
        }
    }
    // Pass 2: accumulate every disc within eps of the visible surface, Gaussian-weighted.
    std::vector<double> acc_z(std::size_t(w) * (row1 - row0), 0.0);
    for (std::int32_t i : bands[band]) {
      const Box& b = boxes[i];
      const double r2 = cloud.radii[i] * cloud.radii[i];
      const double sigma = params.sigma_fraction * cloud.radii[i];
      const double inv2s2 = 1.0 / (2.0 * sigma * sigma);
      const std::array<float, 3> col = cloud.colours.empty() ? std::array<float, 3>{1, 1, 1} : cloud.colours[i];
      for (int y = std::max(row0, b.y0); y <= std::min(row1 - 1, b.y1); ++y)
        for (int x = b.x0; x <= b.x1; ++x) {
          Vec3d o, d;
          cam.pixelRay(x + 0.5, y + 0.5, o, d);
          double t, rho2;
          if (!intersectSplatPlane(o, d, cloud.centers[i], normals[i], t, rho2) || rho2 > r2) continue;
          const double z = t * dot(d, cam.forward);
          const std::size_t p = std::size_t(y) * w + x;
          if (z > double(out.nearest_depth[p]) + eps) continue;
          const double wgt = std::exp(-rho2 * inv2s2);
          const Vec3d nv = dot(normals[i], d) > 0.0 ? -normals[i] : normals[i];
          out.weight[p] += float(wgt);
          acc_z[std::size_t(y - row0) * w + x] += wgt * z;
          for (int k = 0; k < 3; ++k) {
            out.rgb[3 * p + k] += float(wgt * col[k]);
            out.normal[3 * p + k] += float(wgt * nv[k]);
          }
        }
    }
    for (int y = row0; y < row1; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t p = std::size_t(y) * w + x;
        const float wsum = out.weight[p];
        if (!(wsum > 0.0f)) continue;
        out.blended_depth[p] = float(acc_z[std::size_t(y - row0) * w + x] / wsum);
        for (int k = 0; k < 3; ++k) out.rgb[3 * p + k] /= wsum;
        const Vec3d nn =
            normalizeOr(Vec3d{out.normal[3 * p], out.normal[3 * p + 1], out.normal[3 * p + 2]}, -cam.forward);
        for (int k = 0; k < 3; ++k) out.normal[3 * p + k] = float(nn[k]);
      }
  });
}

}  // namespace inc::viewer
