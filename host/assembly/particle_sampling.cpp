// Lattice sampling of boxes, ellipsoids and closed meshes (winding number along +z rays) into particles.
#include "host/assembly/particle_sampling.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "model/input_error.h"

namespace inc {

namespace {

// SplitMix64: a stateless hash, so each sample's jitter depends only on (seed, lattice index, axis).
std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Uniform in [-1, 1).
double hashUnit(unsigned seed, std::int64_t i, std::int64_t j, std::int64_t k, int axis) {
  std::uint64_t h = mix64(std::uint64_t(seed) * 0x100000001b3ull + std::uint64_t(axis));
  h = mix64(h ^ std::uint64_t(i));
  h = mix64(h ^ std::uint64_t(j));
  h = mix64(h ^ std::uint64_t(k));
  return double(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

Vec3d jitterOffset(const LatticeSpec& l, std::int64_t i, std::int64_t j, std::int64_t k) {
  if (l.jitter <= 0) return {};
  const double a = l.jitter * l.spacing;
  return {a * hashUnit(l.seed, i, j, k, 0), a * hashUnit(l.seed, i, j, k, 1), a * hashUnit(l.seed, i, j, k, 2)};
}

// Edge function of (px, py) against the directed edge a -> b, evaluated in a canonical endpoint order so
// that the two triangles sharing an edge get exactly opposite values (robust half-open rule).
double edgeFunction(const Vec3d& a, const Vec3d& b, double px, double py) {
  const bool swap = (b.x < a.x) || (b.x == a.x && b.y < a.y);
  const Vec3d& p0 = swap ? b : a;
  const Vec3d& p1 = swap ? a : b;
  const double e = (p1.x - p0.x) * (py - p0.y) - (p1.y - p0.y) * (px - p0.x);
  return swap ? -e : e;
}

// Top-left rule for a counter-clockwise (seen from +z) triangle: a point exactly on an edge belongs to
// the triangle when the edge points "up-left", so the plane is partitioned without double counting.
bool insideEdge(const Vec3d& a, const Vec3d& b, double px, double py) {
  const double e = edgeFunction(a, b, px, py);
  if (e != 0.0) return e > 0.0;
  const double dx = b.x - a.x, dy = b.y - a.y;
  return dy < 0.0 || (dy == 0.0 && dx > 0.0);
}

// Signed crossing of the +z ray from column (px, py) with triangle (a, b, c): returns 0 when missed, else
// +1 (face seen counter-clockwise from +z, i.e. outward normal up) or -1, and the crossing height in z.
int crossColumn(Vec3d a, Vec3d b, Vec3d c, double px, double py, double& z) {
  const double area2 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  if (area2 == 0.0) return 0;  // edge-on face: its neighbours carry the crossing
  int sign = 1;
  if (area2 < 0.0) {
    std::swap(b, c);
    sign = -1;
  }
  if (!insideEdge(a, b, px, py) || !insideEdge(b, c, px, py) || !insideEdge(c, a, px, py)) return 0;
  const double wa = edgeFunction(b, c, px, py), wb = edgeFunction(c, a, px, py), wc = edgeFunction(a, b, px, py);
  const double s = wa + wb + wc;
  z = (wa * a.z + wb * b.z + wc * c.z) / s;
  return sign;
}

void requireGeometry(bool ok, const std::string& file, const std::string& key, const std::string& reason) {
  if (!ok) throw InputError(file, key, reason);
}

}  // namespace

std::vector<Vec3d> sampleBox(const Vec3d& center, const Vec3d& size, const LatticeSpec& l) {
  std::int64_t n[3];
  for (int a = 0; a < 3; ++a) n[a] = std::max<std::int64_t>(1, std::llround(size[a] / l.spacing));
  std::vector<Vec3d> out;
  out.reserve(std::size_t(n[0] * n[1] * n[2]));
  for (std::int64_t k = 0; k < n[2]; ++k)
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i) {
        const Vec3d p(center.x + (double(i) - 0.5 * double(n[0] - 1)) * l.spacing,
                      center.y + (double(j) - 0.5 * double(n[1] - 1)) * l.spacing,
                      center.z + (double(k) - 0.5 * double(n[2] - 1)) * l.spacing);
        out.push_back(p + jitterOffset(l, i, j, k));
      }
  return out;
}

std::vector<Vec3d> sampleEllipsoid(const Vec3d& center, const Vec3d& radii, const LatticeSpec& l) {
  std::int64_t m[3];
  for (int a = 0; a < 3; ++a) m[a] = std::int64_t(std::floor(radii[a] / l.spacing));
  std::vector<Vec3d> out;
  for (std::int64_t k = -m[2]; k <= m[2]; ++k)
    for (std::int64_t j = -m[1]; j <= m[1]; ++j)
      for (std::int64_t i = -m[0]; i <= m[0]; ++i) {
        const Vec3d d(double(i) * l.spacing, double(j) * l.spacing, double(k) * l.spacing);
        const double q =
            (d.x / radii.x) * (d.x / radii.x) + (d.y / radii.y) * (d.y / radii.y) + (d.z / radii.z) * (d.z / radii.z);
        if (q <= 1.0) out.push_back(center + d + jitterOffset(l, i, j, k));
      }
  return out;
}

int meshWindingNumber(const TriangleMesh& mesh, const Vec3d& p) {
  int w = 0;
  for (const auto& t : mesh.triangles) {
    double z = 0;
    const int s = crossColumn(mesh.vertices[std::size_t(t[0])], mesh.vertices[std::size_t(t[1])],
                              mesh.vertices[std::size_t(t[2])], p.x, p.y, z);
    if (s != 0 && z > p.z) w += s;
  }
  return w;
}

std::vector<Vec3d> sampleMesh(const TriangleMesh& mesh, const LatticeSpec& l) {
  std::vector<Vec3d> out;
  if (mesh.vertices.empty() || mesh.triangles.empty()) return out;
  Vec3d lo = mesh.vertices[0], hi = mesh.vertices[0];
  for (const auto& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], v[a]);
      hi[a] = std::max(hi[a], v[a]);
    }
  const double s = l.spacing;
  std::int64_t n[3];
  for (int a = 0; a < 3; ++a) n[a] = std::max<std::int64_t>(1, std::int64_t(std::ceil((hi[a] - lo[a]) / s)));
  // Lattice of cell centres covering the bounding box, centred on it.
  Vec3d origin;
  for (int a = 0; a < 3; ++a) origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * double(n[a] - 1) * s;
  // Bin each face into the columns whose (x, y) its projected bounds cover.
  std::vector<std::vector<std::int32_t>> columns(std::size_t(n[0] * n[1]));
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (int c = 0; c < 3; ++c) {
      const Vec3d& v = mesh.vertices[std::size_t(mesh.triangles[f][std::size_t(c)])];
      x0 = std::min(x0, v.x);
      x1 = std::max(x1, v.x);
      y0 = std::min(y0, v.y);
      y1 = std::max(y1, v.y);
    }
    const std::int64_t i0 = std::max<std::int64_t>(0, std::int64_t(std::ceil((x0 - origin.x) / s)));
    const std::int64_t i1 = std::min<std::int64_t>(n[0] - 1, std::int64_t(std::floor((x1 - origin.x) / s)));
    const std::int64_t j0 = std::max<std::int64_t>(0, std::int64_t(std::ceil((y0 - origin.y) / s)));
    const std::int64_t j1 = std::min<std::int64_t>(n[1] - 1, std::int64_t(std::floor((y1 - origin.y) / s)));
    for (std::int64_t j = j0; j <= j1; ++j)
      for (std::int64_t i = i0; i <= i1; ++i) columns[std::size_t(j * n[0] + i)].push_back(std::int32_t(f));
  }
  // Per column: signed crossings sorted by height; a lattice point's winding number is the sum of the
  // signs of the crossings above it. Points are emitted in (k, j, i) order, x fastest.
  std::vector<std::vector<std::pair<double, int>>> hits(columns.size());
  for (std::size_t c = 0; c < columns.size(); ++c) {
    const double px = origin.x + double(std::int64_t(c) % n[0]) * s;
    const double py = origin.y + double(std::int64_t(c) / n[0]) * s;
    for (const std::int32_t f : columns[c]) {
      const auto& t = mesh.triangles[std::size_t(f)];
      double z = 0;
      const int sg = crossColumn(mesh.vertices[std::size_t(t[0])], mesh.vertices[std::size_t(t[1])],
                                 mesh.vertices[std::size_t(t[2])], px, py, z);
      if (sg != 0) hits[c].push_back({z, sg});
    }
    std::sort(hits[c].begin(), hits[c].end());
  }
  for (std::int64_t k = 0; k < n[2]; ++k) {
    const double pz = origin.z + double(k) * s;
    for (std::int64_t j = 0; j < n[1]; ++j)
      for (std::int64_t i = 0; i < n[0]; ++i) {
        const auto& h = hits[std::size_t(j * n[0] + i)];
        int w = 0;
        for (auto it = h.rbegin(); it != h.rend() && it->first > pz; ++it) w += it->second;
        if (w != 0)
          out.push_back(Vec3d(origin.x + double(i) * s, origin.y + double(j) * s, pz) + jitterOffset(l, i, j, k));
      }
  }
  return out;
}

std::vector<Vec3d> sampleGeometry(const GeometrySpec& g, const std::string& file) {
  requireGeometry(std::isfinite(g.spacing) && g.spacing > 0, file, "geometry.spacing_m", "must be a positive number");
  requireGeometry(std::isfinite(g.jitter) && g.jitter >= 0 && g.jitter < 0.5, file, "geometry.jitter",
                  "must lie in [0, 0.5)");
  requireGeometry(isFinite(g.center), file, "geometry.center_m", "must be finite");
  LatticeSpec l{g.spacing, g.jitter, g.seed};
  // Refuse absurd particle counts before allocating them.
  auto budget = [&](double volume, const std::string& key) {
    const double count = volume / (g.spacing * g.spacing * g.spacing);
    requireGeometry(count <= 2.0e8, file, key,
                    "would sample about " + std::to_string(count) + " particles (limit 2e8); raise geometry.spacing_m");
  };
  std::vector<Vec3d> out;
  switch (g.kind) {
    case GeometrySpec::Kind::Box:
    case GeometrySpec::Kind::Beam:
      requireGeometry(isFinite(g.size) && g.size.x > 0 && g.size.y > 0 && g.size.z > 0, file, "geometry.size_m",
                      "every extent must be > 0");
      budget(g.size.x * g.size.y * g.size.z, "geometry.size_m");
      out = sampleBox(g.center, g.size, l);
      break;
    case GeometrySpec::Kind::Sphere:
      requireGeometry(std::isfinite(g.radius) && g.radius > 0, file, "geometry.radius_m", "must be > 0");
      budget(4.19 * g.radius * g.radius * g.radius, "geometry.radius_m");
      out = sampleEllipsoid(g.center, Vec3d(g.radius, g.radius, g.radius), l);
      break;
    case GeometrySpec::Kind::Ellipsoid:
      requireGeometry(isFinite(g.radii) && g.radii.x > 0 && g.radii.y > 0 && g.radii.z > 0, file, "geometry.radii_m",
                      "every semi-axis must be > 0");
      budget(4.19 * g.radii.x * g.radii.y * g.radii.z, "geometry.radii_m");
      out = sampleEllipsoid(g.center, g.radii, l);
      break;
    case GeometrySpec::Kind::Mesh:
      throw InputError(file, "geometry.kind", "mesh geometry must be loaded and sampled with sampleMesh");
  }
  requireGeometry(!out.empty(), file, "geometry", "sampled no particle (spacing larger than the body?)");
  return out;
}

}  // namespace inc
