// Planar mesh split with shared contour vertices and ear-clipped cut walls (closed, oriented pieces).
#include "host/cut/cut_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "model/input_error.h"

namespace inc {

bool planeOfSweptSurface(const SweptSurface& s, Vec3d& point, Vec3d& normal, double tol) {
  if (s.empty()) return false;
  Vec3d c, n;
  for (const auto& v : s.vertices) c += v;
  c *= 1.0 / double(s.vertices.size());
  for (const auto& t : s.triangles)
    n += cross(s.vertices[t[1]] - s.vertices[t[0]], s.vertices[t[2]] - s.vertices[t[0]]);
  const double len = norm(n);
  if (!(len > 0.0)) return false;
  n *= 1.0 / len;
  for (const auto& v : s.vertices)
    if (std::fabs(dot(v - c, n)) > tol) return false;
  point = c;
  normal = n;
  return true;
}

bool sweptSurfaceSpansSection(const TriangleMesh& mesh, const SweptSurface& s, const Vec3d& point, const Vec3d& normal,
                              double tol) {
  bool any = false;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vec3d a = mesh.vertices[t[k]], b = mesh.vertices[t[(k + 1) % 3]];
      const double sa = dot(a - point, normal), sb = dot(b - point, normal);
      if ((sa > 0) == (sb > 0)) continue;
      any = true;
      if (distanceToSweptSurface(s, a + (b - a) * (sa / (sa - sb))) > tol) return false;
    }
  return any;
}

TriangleMesh mergeMeshes(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh m = a;
  const int off = int(a.vertices.size());
  m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (const auto& t : b.triangles) m.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  return m;
}

namespace {

using Edge = std::pair<int, int>;
Edge key(int a, int b) { return a < b ? Edge{a, b} : Edge{b, a}; }

// Ear clipping of one simple polygon given as 2D coordinates, counter-clockwise; appends index triples.
int earClip(const std::vector<std::array<double, 2>>& p, std::vector<int> poly, std::vector<std::array<int, 3>>& out) {
  int forced = 0;
  const auto cross2 = [&](int a, int b, int c) {
    return (p[b][0] - p[a][0]) * (p[c][1] - p[a][1]) - (p[b][1] - p[a][1]) * (p[c][0] - p[a][0]);
  };
  double scale = 0.0;
  for (int i : poly) scale = std::max({scale, std::fabs(p[i][0]), std::fabs(p[i][1])});
  const double eps = 1e-14 * std::max(scale * scale, 1e-30);
  while (poly.size() > 3) {
    const int n = int(poly.size());
    // Among the valid ears (convex corner, no other vertex inside or on it) take the best shaped one, the largest
    // height / longest edge ratio: a first-found rule leaves slivers along collinear runs of contour vertices.
    int best = -1;
    double best_quality = 0.0;
    const auto len2 = [&](int u, int v) {
      return (p[u][0] - p[v][0]) * (p[u][0] - p[v][0]) + (p[u][1] - p[v][1]) * (p[u][1] - p[v][1]);
    };
    for (int i = 0; i < n; ++i) {
      const int a = poly[(i + n - 1) % n], b = poly[i], c = poly[(i + 1) % n];
      const double area2 = cross2(a, b, c);
      if (area2 <= eps) continue;  // reflex or flat corner
      const double quality = area2 / std::max({len2(a, b), len2(b, c), len2(c, a)});
      if (quality <= best_quality) continue;
      bool empty = true;
      for (int j = 0; j < n && empty; ++j) {
        const int q = poly[j];
        if (q == a || q == b || q == c) continue;
        if (cross2(a, b, q) >= -eps && cross2(b, c, q) >= -eps && cross2(c, a, q) >= -eps) empty = false;
      }
      if (empty) {
        best = i;
        best_quality = quality;
      }
    }
    if (best < 0) {  // no clean ear (numerical trouble): clip the most convex corner so the wall still closes
      ++forced;
      double most = -1e300;
      for (int i = 0; i < n; ++i) {
        const double v = cross2(poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
        if (v > most) most = v, best = i;
      }
    }
    out.push_back({poly[(best + n - 1) % n], poly[best], poly[(best + 1) % n]});
    poly.erase(poly.begin() + best);
  }
  if (poly.size() == 3) out.push_back({poly[0], poly[1], poly[2]});
  return forced;
}

// Signed distances of the vertices from the plane (point, unit n). No vertex may lie within `snap` of the plane,
// else the split leaves slivers next to it: the plane is shifted along n by 3 snap steps until it clears every
// vertex (a sub-micrometre move of the cut for organ sizes; deterministic).
std::vector<double> clearedPlaneDistances(const TriangleMesh& mesh, const Vec3d& point, const Vec3d& n) {
  const std::size_t nv = mesh.vertices.size();
  double size = 0.0;
  for (const auto& v : mesh.vertices) size = std::max(size, norm(v - point));
  const double snap = 1e-7 * std::max(size, 1e-12);
  double shift = 0.0;
  std::vector<double> s(nv);
  for (int attempt = 0; attempt < 64; ++attempt) {
    bool clear = true;
    for (std::size_t i = 0; i < nv; ++i) {
      s[i] = dot(mesh.vertices[i] - point, n) - shift;
      clear = clear && std::fabs(s[i]) >= snap;
    }
    if (clear) break;
    shift += 3.0 * snap;
  }
  for (std::size_t i = 0; i < nv; ++i)
    if (std::fabs(s[i]) < snap) s[i] = s[i] < 0 ? -snap : snap;  // dense vertices after 64 shifts: push off
  return s;
}

// Contour vertices, one per crossed edge, numbered after the mesh vertices (shared by both pieces).
class ContourVertices {
 public:
  ContourVertices(const TriangleMesh& mesh, const std::vector<double>& s) : mesh_(mesh), s_(s) {}
  int of(int a, int b) {
    const Edge k = key(a, b);
    auto it = cut_vertex_.find(k);
    if (it != cut_vertex_.end()) return it->second;
    const double t = s_[k.first] / (s_[k.first] - s_[k.second]);
    contour_.push_back(mesh_.vertices[k.first] + (mesh_.vertices[k.second] - mesh_.vertices[k.first]) * t);
    const int id = int(mesh_.vertices.size() + contour_.size() - 1);
    cut_vertex_.emplace(k, id);
    return id;
  }
  const std::vector<Vec3d>& points() const { return contour_; }

 private:
  const TriangleMesh& mesh_;
  const std::vector<double>& s_;
  std::map<Edge, int> cut_vertex_;
  std::vector<Vec3d> contour_;
};

// The triangles of the piece on the `sign` side of the plane, crossed triangles clipped; `next` receives the cap
// edges from -> to (reverse of the boundary the clipped triangles leave).
void clipPiece(const TriangleMesh& mesh, const std::vector<double>& s, int sign, ContourVertices& cuts,
               std::vector<std::array<int, 3>>& tris, std::map<int, int>& next) {
  for (const auto& t : mesh.triangles) {
    std::array<bool, 3> in;
    for (int k = 0; k < 3; ++k) in[k] = (s[t[k]] > 0.0) == (sign > 0);
    const int count = int(in[0]) + int(in[1]) + int(in[2]);
    if (count == 3) {
      tris.push_back(t);
      continue;
    }
    if (count == 0) continue;
    // Rotate so the lone vertex (inside for count 1, outside for count 2) comes first, keeping orientation.
    int r0 = 0;
    for (int k = 0; k < 3; ++k)
      if (in[k] == (count == 1)) r0 = k;
    const int a = t[r0], b = t[(r0 + 1) % 3], c = t[(r0 + 2) % 3];
    const int xab = cuts.of(a, b), xca = cuts.of(c, a);
    if (count == 1) {
      tris.push_back({a, xab, xca});
      next[xca] = xab;  // the triangle runs xab -> xca along the cut; the wall runs the other way
    } else {
      tris.push_back({xab, b, c});
      tris.push_back({xab, c, xca});
      next[xab] = xca;  // triangle edge xca -> xab
    }
  }
}

// The piece's cut wall: each closed contour of `next`, projected on the plane with a basis (u, w) such that
// u x w = wall normal (-sign * n, outward for this piece); the loops then run counter-clockwise. Counts its loops
// and forced ears into r.
std::vector<std::array<int, 3>> capPiece(const std::map<int, int>& next, const std::vector<Vec3d>& contour,
                                         std::size_t nv, const Vec3d& point, const Vec3d& n, int sign,
                                         CutMeshResult& r) {
  const Vec3d wall_n = n * double(-sign);
  const Vec3d helper = std::fabs(wall_n.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
  Vec3d u = cross(helper, wall_n);
  u *= 1.0 / norm(u);
  const Vec3d w = cross(wall_n, u);
  std::vector<std::array<double, 2>> p2(nv + contour.size());
  for (std::size_t i = 0; i < contour.size(); ++i) {
    const Vec3d d = contour[i] - point;
    p2[nv + i] = {dot(d, u), dot(d, w)};
  }
  std::map<int, bool> used;
  int loops = 0;
  std::vector<std::array<int, 3>> wall;
  for (const auto& e : next) {
    if (used[e.first]) continue;
    std::vector<int> loop;
    int v = e.first;
    while (!used[v]) {
      used[v] = true;
      loop.push_back(v);
      auto it = next.find(v);
      if (it == next.end()) throw InputError("cut", "mesh", "the surface is not closed along the cut (open contour)");
      v = it->second;
    }
    ++loops;
    if (loop.size() < 3) continue;
    r.forced_ears += earClip(p2, loop, wall);
  }
  r.contour_loops = std::max(r.contour_loops, loops);
  r.wall_triangles += int(wall.size());
  return wall;
}

// The piece as a mesh of the vertices it uses only.
void compactPiece(std::vector<std::array<int, 3>>& tris, const TriangleMesh& mesh, const std::vector<Vec3d>& contour,
                  TriangleMesh& out) {
  const std::size_t nv = mesh.vertices.size();
  std::vector<int> remap(nv + contour.size(), -1);
  for (auto& t : tris) {
    for (int k = 0; k < 3; ++k) {
      int& id = remap[t[k]];
      if (id < 0) {
        id = int(out.vertices.size());
        out.vertices.push_back(t[k] < int(nv) ? mesh.vertices[t[k]] : contour[t[k] - nv]);
      }
      t[k] = id;
    }
    out.triangles.push_back(t);
  }
}

}  // namespace

CutMeshResult splitMeshByPlane(const TriangleMesh& mesh, const Vec3d& point, const Vec3d& normal_in) {
  const double nl = norm(normal_in);
  if (!(nl > 0.0) || !isFinite(point)) throw InputError("cut", "plane", "normal must be non-zero and finite");
  const Vec3d n = normal_in * (1.0 / nl);
  const std::vector<double> s = clearedPlaneDistances(mesh, point, n);
  ContourVertices cuts(mesh, s);
  CutMeshResult r;
  for (int sign : {+1, -1}) {
    std::vector<std::array<int, 3>> tris;
    std::map<int, int> next;
    clipPiece(mesh, s, sign, cuts, tris, next);
    const std::vector<std::array<int, 3>> wall = capPiece(next, cuts.points(), mesh.vertices.size(), point, n, sign, r);
    tris.insert(tris.end(), wall.begin(), wall.end());
    compactPiece(tris, mesh, cuts.points(), sign > 0 ? r.positive : r.negative);
  }
  return r;
}

}  // namespace inc
