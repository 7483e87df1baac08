// Unfolding of the blade strip into its parameter domain; projections of 3D points into it and lifts back.
#include "host/cut/cut_sweep_domain.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "model/input_error.h"

namespace inc {

namespace {

[[noreturn]] void bad(const std::string& reason) { throw InputError("cut", "swept surface", reason); }

double cross2(const Vec2d& o, const Vec2d& a, const Vec2d& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// The point P with |P - X| = dx and |P - Y| = dy such that (X, Y, P) is counter-clockwise (P left of X -> Y).
Vec2d placeLeft(const Vec2d& X, const Vec2d& Y, double dx, double dy) {
  const double ex = Y[0] - X[0], ey = Y[1] - X[1];
  const double L = std::hypot(ex, ey);
  if (!(L > 0.0)) bad("two consecutive blade poses share a point where the strip needs an edge");
  const double a = (dx * dx - dy * dy + L * L) / (2.0 * L);
  const double h = std::sqrt(std::max(0.0, dx * dx - a * a));
  return {X[0] + (a * ex - h * ey) / L, X[1] + (a * ey + h * ex) / L};
}

// Proper or touching intersection of the closed segments ab and cd.
bool segmentsMeet(const Vec2d& a, const Vec2d& b, const Vec2d& c, const Vec2d& d) {
  const double d1 = cross2(a, b, c), d2 = cross2(a, b, d), d3 = cross2(c, d, a), d4 = cross2(c, d, b);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  const auto on = [](const Vec2d& p, const Vec2d& q, const Vec2d& r, double cr) {  // r on segment pq, collinear
    return cr == 0.0 && std::min(p[0], q[0]) <= r[0] && r[0] <= std::max(p[0], q[0]) && std::min(p[1], q[1]) <= r[1] &&
           r[1] <= std::max(p[1], q[1]);
  };
  return on(a, b, c, d1) || on(a, b, d, d2) || on(c, d, a, d3) || on(c, d, b, d4);
}

// Barycentric coordinates (b1, b2) of uv in the unfolded triangle t (b0 = 1 - b1 - b2), extended outside it.
void domainBarycentric(const SweepDomain& d, const std::array<int, 3>& t, const Vec2d& uv, double& b1, double& b2) {
  const Vec2d &p0 = d.uv[t[0]], &p1 = d.uv[t[1]], &p2 = d.uv[t[2]];
  const double det = cross2(p0, p1, p2);
  b1 = cross2(p0, uv, p2) / det;
  b2 = cross2(p0, p1, uv) / det;
}

}  // namespace

SweepDomain unfoldSweptSurface(const SweptSurface& s) {
  const int nv = int(s.vertices.size());
  if (nv < 4 || nv % 2 != 0)
    bad("needs at least two blade poses (base, tip per pose), got " + std::to_string(nv) + " vertices");
  if (s.triangles.empty()) bad("empty: the blade did not move");
  for (int i = 0; i < nv; ++i)
    if (!isFinite(s.vertices[i])) bad("vertex " + std::to_string(i) + " is not finite");
  for (std::size_t i = 0; i < s.triangles.size(); ++i) {
    const auto& t = s.triangles[i];
    const int k = t[0] / 2;
    const bool first = t[0] % 2 == 0 && t[1] == 2 * k + 2 && t[2] == 2 * k + 1;
    const bool second = t[0] % 2 == 1 && t[1] == 2 * k + 2 && t[2] == 2 * k + 3;
    if (!(first || second) || t[2] >= nv || t[1] >= nv)
      bad("triangle " + std::to_string(i) + " is not part of the blade strip (see SweptSurface)");
    const Vec3d& a = s.vertices[t[0]];
    if (!(norm2(cross(s.vertices[t[1]] - a, s.vertices[t[2]] - a)) > 1e-24))
      bad("triangle " + std::to_string(i) + " has zero area");
  }
  SweepDomain d;
  d.uv.assign(std::size_t(nv), {0.0, 0.0});
  const auto dist = [&](int i, int j) { return norm(s.vertices[i] - s.vertices[j]); };
  d.uv[1] = {0.0, dist(0, 1)};  // the first blade along +v, the motion then goes towards +u (CCW strip)
  for (int k = 0; 2 * k + 3 < nv; ++k) {
    // (2k, 2k+2, 2k+1) and (2k+1, 2k+2, 2k+3) counter-clockwise, their edge lengths kept.
    d.uv[2 * k + 2] = placeLeft(d.uv[2 * k + 1], d.uv[2 * k], dist(2 * k + 1, 2 * k + 2), dist(2 * k, 2 * k + 2));
    d.uv[2 * k + 3] =
        placeLeft(d.uv[2 * k + 1], d.uv[2 * k + 2], dist(2 * k + 1, 2 * k + 3), dist(2 * k + 2, 2 * k + 3));
  }
  // Outline: base rail forward, last blade, tip rail backward, first blade; repeated points (a blade end that
  // did not move) dropped.
  std::vector<int> outline;
  for (int i = 0; i < nv; i += 2) outline.push_back(i);
  for (int i = nv - 1; i >= 1; i -= 2) outline.push_back(i);
  Vec2d lo = d.uv[0], hi = lo;
  for (const auto& p : d.uv)
    for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  d.diameter = std::hypot(hi[0] - lo[0], hi[1] - lo[1]);
  const double same = 1e-12 * d.diameter;
  for (int id : outline) {
    if (!d.boundary.empty()) {
      const Vec2d &p = d.uv[d.boundary.back()], &q = d.uv[id];
      if (std::hypot(p[0] - q[0], p[1] - q[1]) <= same) continue;
    }
    d.boundary.push_back(id);
  }
  while (d.boundary.size() > 1) {
    const Vec2d &p = d.uv[d.boundary.back()], &q = d.uv[d.boundary.front()];
    if (std::hypot(p[0] - q[0], p[1] - q[1]) > same) break;
    d.boundary.pop_back();
  }
  const int nb = int(d.boundary.size());
  if (nb < 3) bad("the strip has no area");
  d.box_lo = d.box_hi = s.vertices.front();
  for (const auto& v : s.vertices)
    for (int a = 0; a < 3; ++a) d.box_lo[a] = std::min(d.box_lo[a], v[a]), d.box_hi[a] = std::max(d.box_hi[a], v[a]);
  double area2 = 0.0;
  d.boundary_s.assign(std::size_t(nb) + 1, 0.0);
  for (int i = 0; i < nb; ++i) {
    const Vec2d &p = d.uv[d.boundary[i]], &q = d.uv[d.boundary[(i + 1) % nb]];
    area2 += p[0] * q[1] - p[1] * q[0];
    d.boundary_s[i + 1] = d.boundary_s[i] + std::hypot(q[0] - p[0], q[1] - p[1]);
  }
  if (!(area2 > 0.0)) bad("the unfolded strip is not counter-clockwise (the blade turned over its own sweep)");
  for (int i = 0; i < nb; ++i)
    for (int j = i + 2; j < nb; ++j) {
      if (i == 0 && j == nb - 1) continue;  // adjacent through the closing edge
      if (segmentsMeet(d.uv[d.boundary[i]], d.uv[d.boundary[(i + 1) % nb]], d.uv[d.boundary[j]],
                       d.uv[d.boundary[(j + 1) % nb]]))
        bad("the unfolded strip overlaps itself (outline edges " + std::to_string(i) + " and " + std::to_string(j) +
            " meet): the blade path turns back over its own sweep");
    }
  return d;
}

SweepProjection projectOntoSweep(const SweptSurface& s, const SweepDomain& d, const SweptSurfaceQuery& query,
                                 const Vec3d& p) {
  SweepProjection r;
  r.triangle = query.closestTriangle(p, r.closest);
  const auto& t = s.triangles[std::size_t(r.triangle)];
  const Vec3d& a = s.vertices[t[0]];
  const Vec3d e1 = s.vertices[t[1]] - a, e2 = s.vertices[t[2]] - a, w = p - a;
  const Vec3d n = cross(e1, e2);
  r.normal = n * (1.0 / norm(n));
  r.offset = dot(w, r.normal);
  r.distance = std::sqrt(norm2(r.closest - p));
  // Projection onto the triangle's plane in barycentric coordinates (Gram system), then into the domain.
  const double g11 = dot(e1, e1), g12 = dot(e1, e2), g22 = dot(e2, e2), r1 = dot(w, e1), r2 = dot(w, e2);
  const double det = g11 * g22 - g12 * g12;
  const double b1 = (r1 * g22 - r2 * g12) / det, b2 = (r2 * g11 - r1 * g12) / det;
  const Vec2d &u0 = d.uv[t[0]], &u1 = d.uv[t[1]], &u2 = d.uv[t[2]];
  r.uv = {u0[0] + b1 * (u1[0] - u0[0]) + b2 * (u2[0] - u0[0]), u0[1] + b1 * (u1[1] - u0[1]) + b2 * (u2[1] - u0[1])};
  return r;
}

Vec3d liftFromDomain(const SweptSurface& s, const SweepDomain& d, const Vec2d& uv) {
  int best = -1;
  double best_min = -std::numeric_limits<double>::infinity(), bb1 = 0.0, bb2 = 0.0;
  for (std::size_t i = 0; i < s.triangles.size(); ++i) {
    double b1, b2;
    domainBarycentric(d, s.triangles[i], uv, b1, b2);
    const double m = std::min({1.0 - b1 - b2, b1, b2});
    if (m > best_min) {
      best_min = m;
      best = int(i);
      bb1 = b1;
      bb2 = b2;
      if (m >= 0.0) break;  // inside this triangle
    }
  }
  const auto& t = s.triangles[std::size_t(best)];
  const Vec3d& a = s.vertices[t[0]];
  return a + (s.vertices[t[1]] - a) * bb1 + (s.vertices[t[2]] - a) * bb2;
}

double outlinePosition(const SweepDomain& d, const Vec2d& uv) {
  const int nb = int(d.boundary.size());
  double best = std::numeric_limits<double>::infinity(), pos = 0.0;
  for (int i = 0; i < nb; ++i) {
    const Vec2d &p = d.uv[d.boundary[i]], &q = d.uv[d.boundary[(i + 1) % nb]];
    const double ex = q[0] - p[0], ey = q[1] - p[1], l2 = ex * ex + ey * ey;
    const double t = std::clamp(((uv[0] - p[0]) * ex + (uv[1] - p[1]) * ey) / l2, 0.0, 1.0);
    const double dd = std::hypot(p[0] + t * ex - uv[0], p[1] + t * ey - uv[1]);
    if (dd < best) {
      best = dd;
      pos = d.boundary_s[i] + t * (d.boundary_s[i + 1] - d.boundary_s[i]);
    }
  }
  return pos;
}

Vec2d outlinePoint(const SweepDomain& d, double s, Vec2d* outward) {
  const int nb = int(d.boundary.size());
  const double per = d.perimeter();
  s = std::fmod(s, per);
  if (s < 0.0) s += per;
  int i = int(std::upper_bound(d.boundary_s.begin(), d.boundary_s.end(), s) - d.boundary_s.begin()) - 1;
  i = std::clamp(i, 0, nb - 1);
  const Vec2d &p = d.uv[d.boundary[i]], &q = d.uv[d.boundary[(i + 1) % nb]];
  const double len = d.boundary_s[i + 1] - d.boundary_s[i];
  const double t = std::clamp((s - d.boundary_s[i]) / len, 0.0, 1.0);
  if (outward) *outward = {(q[1] - p[1]) / len, -(q[0] - p[0]) / len};  // right of a CCW edge
  return {p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])};
}

bool insideOutline(const SweepDomain& d, const Vec2d& uv) {
  bool in = false;
  const int nb = int(d.boundary.size());
  for (int i = 0, j = nb - 1; i < nb; j = i++) {
    const Vec2d &a = d.uv[d.boundary[i]], &b = d.uv[d.boundary[j]];
    if ((a[1] > uv[1]) != (b[1] > uv[1]) && uv[0] < (b[0] - a[0]) * (uv[1] - a[1]) / (b[1] - a[1]) + a[0]) in = !in;
  }
  return in;
}

}  // namespace inc
