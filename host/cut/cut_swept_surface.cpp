// Swept-surface construction and the segment / sphere / side queries the cut uses (CPU, O(triangles) per query).
#include "host/cut/cut_swept_surface.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "base/parallel.h"
#include "model/input_error.h"
#include "physics/cut_geometry.h"

namespace inc {

namespace {
void checkPose(const BladePose& p, std::size_t k) {
  if (!isFinite(p.base) || !isFinite(p.tip))
    throw InputError("cut", "blade", "pose " + std::to_string(k) + " is not finite");
  if (!(norm(p.tip - p.base) > 1e-9))
    throw InputError("cut", "blade", "pose " + std::to_string(k) + " has a zero-length blade");
}
}  // namespace

SweptSurface sweepSurface(const std::vector<BladePose>& poses) {
  if (poses.size() < 2) throw InputError("cut", "blade", "a swept surface needs at least 2 poses");
  SweptSurface s;
  checkPose(poses[0], 0);
  s.vertices.push_back(poses[0].base);
  s.vertices.push_back(poses[0].tip);
  for (std::size_t k = 1; k < poses.size(); ++k) {
    checkPose(poses[k], k);
    extendSweptSurface(s, poses[k]);
  }
  return s;
}

void extendSweptSurface(SweptSurface& s, const BladePose& next) {
  checkPose(next, s.vertices.size() / 2);
  if (s.vertices.size() < 2 || s.vertices.size() % 2 != 0)
    throw InputError("cut", "blade", "swept surface must start from one full pose");
  const int k = int(s.vertices.size()) - 2;  // base of the previous pose
  s.vertices.push_back(next.base);
  s.vertices.push_back(next.tip);
  const auto area2 = [&](int a, int b, int c) {
    return norm2(cross(s.vertices[b] - s.vertices[a], s.vertices[c] - s.vertices[a]));
  };
  // A blade that did not move adds no degenerate triangles.
  if (area2(k, k + 2, k + 1) > 1e-24) s.triangles.push_back({k, k + 2, k + 1});
  if (area2(k + 1, k + 2, k + 3) > 1e-24) s.triangles.push_back({k + 1, k + 2, k + 3});
}

namespace {
// One swept triangle against a segment, with its box (margin far above the widened barycentric bounds) and its
// plane normal given. Both ends clearly on one side of the plane (by more than 1e-6 of their distance to a
// corner, far above rounding) means no crossing without the full test.
bool crossesTriangle(const Vec3d& p, const Vec3d& q, const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& lo,
                     const Vec3d& hi, const Vec3d& n) {
  for (int k = 0; k < 3; ++k)
    if (std::max(p[k], q[k]) < lo[k] || std::min(p[k], q[k]) > hi[k]) return false;
  const double dp = dot(n, p - a), dq = dot(n, q - a);
  if (dp * dq > 0) {
    const double m = 1e-12 * norm2(n);
    if (dp * dp > m * norm2(p - a) && dq * dq > m * norm2(q - a)) return false;
  }
  return cut::segmentCrossesTriangle(p, q, a, b, c);
}
void triangleBox(const Vec3d& a, const Vec3d& b, const Vec3d& c, Vec3d& lo, Vec3d& hi) {
  for (int k = 0; k < 3; ++k) {
    const double l = std::min({a[k], b[k], c[k]}), h = std::max({a[k], b[k], c[k]});
    const double m = 1e-6 * (h - l) + 1e-12;
    lo[k] = l - m;
    hi[k] = h + m;
  }
}
}  // namespace

bool segmentCrossesSweptSurface(const SweptSurface& s, const Vec3d& p, const Vec3d& q) {
  for (const auto& t : s.triangles) {
    const Vec3d& a = s.vertices[t[0]];
    const Vec3d& b = s.vertices[t[1]];
    const Vec3d& c = s.vertices[t[2]];
    Vec3d lo, hi;
    triangleBox(a, b, c, lo, hi);
    if (crossesTriangle(p, q, a, b, c, lo, hi, cross(b - a, c - a))) return true;
  }
  return false;
}

SweptSurfaceQuery::SweptSurfaceQuery(const SweptSurface& s) : s_(s) {
  const std::size_t nt = s.triangles.size();
  lo_.resize(nt);
  hi_.resize(nt);
  n_.resize(nt);
  for (std::size_t i = 0; i < nt; ++i) {
    const auto& t = s.triangles[i];
    triangleBox(s.vertices[t[0]], s.vertices[t[1]], s.vertices[t[2]], lo_[i], hi_[i]);
    n_[i] = cross(s.vertices[t[1]] - s.vertices[t[0]], s.vertices[t[2]] - s.vertices[t[0]]);
  }
  for (std::size_t b = 0; b < nt; b += kBlock) {
    Vec3d lo = lo_[b], hi = hi_[b];
    for (std::size_t i = b; i < std::min(nt, b + kBlock); ++i)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], lo_[i][k]), hi[k] = std::max(hi[k], hi_[i][k]);
    block_lo_.push_back(lo);
    block_hi_.push_back(hi);
  }
}

bool SweptSurfaceQuery::segmentCrosses(const Vec3d& p, const Vec3d& q) const {
  const std::size_t nt = s_.triangles.size();
  const Vec3d slo(std::min(p.x, q.x), std::min(p.y, q.y), std::min(p.z, q.z));
  const Vec3d shi(std::max(p.x, q.x), std::max(p.y, q.y), std::max(p.z, q.z));
  for (std::size_t b = 0; b < block_lo_.size(); ++b) {
    const Vec3d& lo = block_lo_[b];
    const Vec3d& hi = block_hi_[b];
    if (shi.x < lo.x || slo.x > hi.x || shi.y < lo.y || slo.y > hi.y || shi.z < lo.z || slo.z > hi.z) continue;
    for (std::size_t i = b * kBlock; i < std::min(nt, (b + 1) * kBlock); ++i) {
      const auto& t = s_.triangles[i];
      if (crossesTriangle(p, q, s_.vertices[t[0]], s_.vertices[t[1]], s_.vertices[t[2]], lo_[i], hi_[i], n_[i]))
        return true;
    }
  }
  return false;
}

namespace {
// Squared distance from p to the box [lo, hi] (0 inside).
double boxDistance2(const Vec3d& p, const Vec3d& lo, const Vec3d& hi) {
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double e = p[k] < lo[k] ? lo[k] - p[k] : (p[k] > hi[k] ? p[k] - hi[k] : 0.0);
    d2 += e * e;
  }
  return d2;
}
}  // namespace

int SweptSurfaceQuery::closestTriangle(const Vec3d& p, Vec3d& closest) const {
  const std::size_t nt = s_.triangles.size(), nb = block_lo_.size();
  if (nt == 0) return -1;
  double best = std::numeric_limits<double>::infinity();
  int best_t = -1;
  const auto scan = [&](std::size_t b) {
    for (std::size_t i = b * kBlock; i < std::min(nt, (b + 1) * kBlock); ++i) {
      const auto& t = s_.triangles[i];
      const Vec3d k = cut::closestPointOnTriangle(p, s_.vertices[t[0]], s_.vertices[t[1]], s_.vertices[t[2]]);
      const double d2 = norm2(k - p);
      if (d2 < best || (d2 == best && int(i) < best_t)) best = d2, best_t = int(i), closest = k;
    }
  };
  // The nearest run first, so that the bound prunes most of the others.
  std::size_t first = 0;
  double first_d2 = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < nb; ++b) {
    const double d2 = boxDistance2(p, block_lo_[b], block_hi_[b]);
    if (d2 < first_d2) first_d2 = d2, first = b;
  }
  scan(first);
  // A run whose padded box lies farther than the best triangle holds no triangle as close (computed distances
  // of points inside a box exceed its rounding-free margin), so skipping it changes neither the distance nor,
  // with the index tie-break, the triangle.
  for (std::size_t b = 0; b < nb; ++b)
    if (b != first && !(boxDistance2(p, block_lo_[b], block_hi_[b]) > best)) scan(b);
  return best_t;
}

double SweptSurfaceQuery::distance(const Vec3d& p) const {
  Vec3d k;
  if (closestTriangle(p, k) < 0) return std::numeric_limits<double>::infinity();
  return norm(k - p);
}

namespace {
// Closest triangle and the closest point on it.
int closestTriangle(const SweptSurface& s, const Vec3d& p, Vec3d& closest) {
  double best = std::numeric_limits<double>::infinity();
  int best_t = -1;
  for (std::size_t i = 0; i < s.triangles.size(); ++i) {
    const auto& t = s.triangles[i];
    const Vec3d k = cut::closestPointOnTriangle(p, s.vertices[t[0]], s.vertices[t[1]], s.vertices[t[2]]);
    const double d2 = norm2(k - p);
    if (d2 < best) {
      best = d2;
      best_t = int(i);
      closest = k;
    }
  }
  return best_t;
}
}  // namespace

int sideOfSweptSurface(const SweptSurface& s, const Vec3d& p) {
  Vec3d k;
  const int ti = closestTriangle(s, p, k);
  if (ti < 0) return 1;
  const auto& t = s.triangles[ti];
  const Vec3d n = cross(s.vertices[t[1]] - s.vertices[t[0]], s.vertices[t[2]] - s.vertices[t[0]]);
  // Offset from the triangle's plane (not from the closest point): beyond the strip's edges the plane still
  // separates the two sides, and a point exactly on the surface goes to +1 (ties are decided one way).
  return dot(p - s.vertices[t[0]], n) >= 0.0 ? 1 : -1;
}

double distanceToSweptSurface(const SweptSurface& s, const Vec3d& p) {
  Vec3d k;
  if (closestTriangle(s, p, k) < 0) return std::numeric_limits<double>::infinity();
  return norm(k - p);
}

bool closestOnSweptSurface(const SweptSurface& s, const Vec3d& p, Vec3d& closest, Vec3d& normal) {
  const int ti = closestTriangle(s, p, closest);
  if (ti < 0) return false;
  const auto& t = s.triangles[ti];
  normal = cross(s.vertices[t[1]] - s.vertices[t[0]], s.vertices[t[2]] - s.vertices[t[0]]);
  normal *= 1.0 / norm(normal);
  return true;
}

std::vector<std::int32_t> findCutSpheres(const SweptSurface& s, const std::vector<Vec3d>& centres,
                                         const std::vector<double>& radii) {
  std::vector<char> hit(centres.size(), 0);
  cpu::parallelFor(std::int64_t(centres.size()), [&](std::int64_t i) {
    for (const auto& t : s.triangles)
      if (cut::sphereTouchesTriangle(centres[i], radii[i], s.vertices[t[0]], s.vertices[t[1]], s.vertices[t[2]])) {
        hit[i] = 1;
        return;
      }
  });
  std::vector<std::int32_t> out;
  for (std::size_t i = 0; i < hit.size(); ++i)
    if (hit[i]) out.push_back(std::int32_t(i));
  return out;
}

std::size_t removeCrossingNeighbours(NeighborLists& lists, const std::vector<Vec3d>& x, const SweptSurface& s) {
  const std::size_t nq = lists.queryCount();
  std::vector<char> keep(lists.indices.size(), 1);
  cpu::parallelFor(std::int64_t(nq), [&](std::int64_t q) {
    for (std::int64_t k = lists.offsets[q]; k < lists.offsets[q + 1]; ++k)
      keep[k] = segmentCrossesSweptSurface(s, x[q], x[lists.indices[k]]) ? 0 : 1;
  });
  NeighborLists out;
  out.offsets.assign(nq + 1, 0);
  for (std::size_t q = 0; q < nq; ++q) {
    for (std::int64_t k = lists.offsets[q]; k < lists.offsets[q + 1]; ++k)
      if (keep[k]) out.indices.push_back(lists.indices[k]);
    out.offsets[q + 1] = std::int64_t(out.indices.size());
  }
  const std::size_t removed = lists.indices.size() - out.indices.size();
  lists = std::move(out);
  return removed;
}

std::size_t removeCrossingLinks(MetaballModel& m, const SweptSurface& s) {
  std::vector<std::array<std::int32_t, 2>> links;
  std::vector<double> rest;
  for (std::size_t l = 0; l < m.links.size(); ++l) {
    const auto& e = m.links[l];
    if (segmentCrossesSweptSurface(s, m.rest_centers[e[0]], m.rest_centers[e[1]])) continue;
    links.push_back(e);
    rest.push_back(m.link_rest_lengths[l]);
  }
  const std::size_t removed = m.links.size() - links.size();
  m.links = std::move(links);
  m.link_rest_lengths = std::move(rest);
  return removed;
}

}  // namespace inc
