// Procedural closed organ-like meshes: geodesic sphere, subdivided box, torus and a liver-like lobed shape.
#include "host/assembly/organ_shapes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <tuple>

#include "model/input_error.h"

namespace inc {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3d normalized(const Vec3d& v) { return v * (1.0 / norm(v)); }

// Icosahedron with counter-clockwise faces seen from outside.
void icosahedron(std::vector<Vec3d>& v, std::vector<std::array<int, 3>>& f) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
       {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p = normalized(p);
  f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
       {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
}

// Unit geodesic sphere of the given frequency. Vertices on an icosahedron edge are keyed by the edge's
// ordered end points and the lattice step from the lower end, so that both faces share them exactly.
TriangleMesh unitGeodesic(int frequency) {
  const int n = std::max(1, frequency);
  std::vector<Vec3d> corners;
  std::vector<std::array<int, 3>> faces;
  icosahedron(corners, faces);
  TriangleMesh mesh;
  mesh.vertices = corners;
  std::map<std::tuple<int, int, int>, int> edge_vertex;  // (lo corner, hi corner, step from lo)
  auto edgePoint = [&](int a, int b, int step) -> int {  // point `step` of n from corner a towards b
    if (step == 0) return a;
    if (step == n) return b;
    const int lo = std::min(a, b), hi = std::max(a, b);
    const int s = (a == lo) ? step : n - step;
    auto key = std::make_tuple(lo, hi, s);
    auto it = edge_vertex.find(key);
    if (it != edge_vertex.end()) return it->second;
    const Vec3d p = corners[lo] + (corners[hi] - corners[lo]) * (double(s) / n);
    mesh.vertices.push_back(normalized(p));
    const int id = int(mesh.vertices.size()) - 1;
    edge_vertex.emplace(key, id);
    return id;
  };
  std::vector<int> lattice;
  for (const auto& face : faces) {
    const int A = face[0], B = face[1], C = face[2];
    lattice.assign(std::size_t((n + 1) * (n + 1)), -1);
    auto at = [&](int i, int j) -> int& { return lattice[std::size_t(i * (n + 1) + j)]; };
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        int id;
        if (j == 0)
          id = edgePoint(A, B, i);
        else if (i == 0)
          id = edgePoint(A, C, j);
        else if (i + j == n)
          id = edgePoint(B, C, j);
        else {
          const Vec3d p =
              corners[A] + (corners[B] - corners[A]) * (double(i) / n) + (corners[C] - corners[A]) * (double(j) / n);
          mesh.vertices.push_back(normalized(p));
          id = int(mesh.vertices.size()) - 1;
        }
        at(i, j) = id;
      }
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        if (i + j < n - 1) mesh.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
  }
  return mesh;
}

int frequencyFor(int target_vertices) {
  return std::max(1, int(std::lround(std::sqrt(std::max(0.0, double(target_vertices) - 2.0) / 10.0))));
}

// Reproducible uniform numbers in [0, 1) from a 64-bit LCG (the standard distributions are not
// specified bit-for-bit across standard libraries).
struct Lcg {
  std::uint64_t s;
  double next() {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(s >> 11) * (1.0 / 9007199254740992.0);
  }
};

struct Bump {
  Vec3d dir;         // unit direction of the bump centre
  double amplitude;  // relative change of the radius at the centre
  double width;      // angular width (radians, roughly)
};

}  // namespace

TriangleMesh makeSphereMesh(double radius_m, int frequency, Vec3d center) {
  TriangleMesh mesh = unitGeodesic(frequency);
  for (auto& p : mesh.vertices) p = center + p * radius_m;
  return mesh;
}

TriangleMesh makeBoxMesh(const Vec3d& half_extents_m, int divisions, Vec3d center) {
  const int n = std::max(1, divisions);
  TriangleMesh mesh;
  std::map<std::tuple<int, int, int>, int> ids;
  auto vertex = [&](int i, int j, int k) -> int {
    auto key = std::make_tuple(i, j, k);
    auto it = ids.find(key);
    if (it != ids.end()) return it->second;
    const int idx[3] = {i, j, k};
    Vec3d p;
    for (int a = 0; a < 3; ++a) p[a] = center[a] + half_extents_m[a] * (-1.0 + 2.0 * idx[a] / n);
    mesh.vertices.push_back(p);
    ids.emplace(key, int(mesh.vertices.size()) - 1);
    return int(mesh.vertices.size()) - 1;
  };
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;  // e_b x e_c = e_a
    for (int side = 0; side <= n; side += n) {
      for (int u = 0; u < n; ++u)
        for (int v = 0; v < n; ++v) {
          int q[4];
          const int uv[4][2] = {{u, v}, {u + 1, v}, {u + 1, v + 1}, {u, v + 1}};
          for (int m = 0; m < 4; ++m) {
            int idx[3];
            idx[a] = side;
            idx[b] = uv[m][0];
            idx[c] = uv[m][1];
            q[m] = vertex(idx[0], idx[1], idx[2]);
          }
          if (side == n) {  // outward +e_a: counter-clockwise in (b, c)
            mesh.triangles.push_back({q[0], q[1], q[2]});
            mesh.triangles.push_back({q[0], q[2], q[3]});
          } else {
            mesh.triangles.push_back({q[0], q[2], q[1]});
            mesh.triangles.push_back({q[0], q[3], q[2]});
          }
        }
    }
  }
  return mesh;
}

TriangleMesh makeTorusMesh(double major_radius_m, double minor_radius_m, int major_segments, int minor_segments,
                           Vec3d center) {
  const int nu = std::max(3, major_segments), nv = std::max(3, minor_segments);
  TriangleMesh mesh;
  mesh.vertices.reserve(std::size_t(nu * nv));
  for (int i = 0; i < nu; ++i) {
    const double u = 2.0 * kPi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double v = 2.0 * kPi * j / nv;
      const double rho = major_radius_m + minor_radius_m * std::cos(v);
      mesh.vertices.push_back(center + Vec3d{rho * std::cos(u), rho * std::sin(u), minor_radius_m * std::sin(v)});
    }
  }
  auto id = [&](int i, int j) { return ((i % nu) * nv) + (j % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {  // dp/du x dp/dv points outward
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return mesh;
}

TriangleMesh makeLiverLikeMesh(const LiverLikeOptions& options) {
  TriangleMesh mesh = unitGeodesic(frequencyFor(options.target_vertices));
  // Radial bumps on the unit sphere (x: patient left(-) to right(+), y: up, z: anterior).
  std::vector<Bump> bumps = {
      {normalized({1.0, 0.15, -0.1}), 0.30, 0.75},    // large right lobe
      {normalized({0.6, 0.45, -0.55}), 0.12, 0.55},   // posterior dome of the right lobe
      {normalized({-1.0, 0.05, 0.25}), 0.10, 0.45},   // tip of the left lobe
      {normalized({-0.25, 0.55, 0.8}), -0.16, 0.28},  // notch between the lobes (falciform side)
      {normalized({-0.2, -0.7, 0.1}), -0.12, 0.45},   // hilum hollow on the underside
      {normalized({0.45, -0.6, 0.6}), 0.05, 0.30},    // quadrate-like lobe
      {normalized({0.2, -0.5, -0.8}), 0.06, 0.30},    // caudate-like lobe
      {normalized({0.0, 0.2, 1.0}), -0.08, 0.40},     // thinner anterior border
  };
  if (options.variant != 0) {
    Lcg rng{0x9E3779B97F4A7C15ULL ^ std::uint64_t(options.variant)};
    for (auto& b : bumps) {
      b.amplitude *= 0.7 + 0.6 * rng.next();
      b.dir = normalized(b.dir + Vec3d{rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5} * 0.3);
    }
  }
  for (auto& p : mesh.vertices) {
    double r = 1.0;  // star-shaped radial field, r(d) > 0.5 > 0 for these amplitudes
    for (const auto& b : bumps) {
      const double c = dot(p, b.dir);  // cos of the angle to the bump centre
      r += b.amplitude * std::exp((c - 1.0) / (b.width * b.width));
    }
    Vec3d q = p * r;
    q = Vec3d{q.x * 0.5, q.y * 0.30, q.z * 0.36};  // positive anisotropic scale
    // Taper: the left lobe thins towards its tip (factor in [0.45, 1], > 0, so injective in y).
    const double taper = 0.45 + 0.55 / (1.0 + std::exp(-(q.x + 0.12) / 0.12));
    q.y *= taper;
    // Shear of y by a function of (x, z): domed diaphragmatic top, concave visceral underside.
    q.y += 0.10 * std::exp(-(q.x * q.x) / 0.08 - (q.z * q.z) / 0.06) - 0.10 * q.x * q.x;
    p = q;
  }
  // Scale to the requested width along x and centre the bounding box at the origin.
  Vec3d lo = mesh.vertices[0], hi = mesh.vertices[0];
  for (const auto& p : mesh.vertices)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  const double s = options.width_m / (hi.x - lo.x);
  const Vec3d mid = (lo + hi) * 0.5;
  for (auto& p : mesh.vertices) p = (p - mid) * s;
  return mesh;
}

TriangleMesh makeOrganShape(const std::string& name, double size_m, int resolution, const std::string& file,
                            const std::string& key) {
  if (!(size_m > 0.0) || !std::isfinite(size_m))
    throw InputError(file, key, "size must be a positive number of metres, got " + std::to_string(size_m));
  if (resolution < 12) throw InputError(file, key, "resolution must be at least 12 vertices");
  if (name == "sphere") return makeSphereMesh(0.5 * size_m, frequencyFor(resolution));
  if (name == "box") {
    const int n = std::max(1, int(std::lround(std::sqrt((resolution - 2) / 6.0))));
    return makeBoxMesh(Vec3d{0.5, 0.35, 0.25} * size_m, n);
  }
  if (name == "torus") {  // tube radius 0.15 size, outer diameter = size; segments in ratio 5:2
    const int minor = std::max(3, int(std::lround(std::sqrt(resolution / 2.5))));
    const int major = std::max(3, int(std::lround(resolution / double(minor))));
    return makeTorusMesh(0.35 * size_m, 0.15 * size_m, major, minor);
  }
  if (name == "liver") {
    LiverLikeOptions o;
    o.target_vertices = resolution;
    o.width_m = size_m;
    return makeLiverLikeMesh(o);
  }
  throw InputError(file, key, "unknown shape '" + name + "' (expected sphere, box, torus or liver)");
}

}  // namespace inc
