// bindSkin: exact k-nearest spheres by signed sphere distance through a centre grid, distance-field weights, normal
// adjacency.
#include "host/assembly/skin_binding.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <utility>

#include "base/parallel.h"
#include "model/input_error.h"

namespace inc {
namespace {

// Uniform grid of sphere centres for shell-by-shell k-nearest search on d_i = |p - c_i| - r_i.
class CentreGrid {
 public:
  CentreGrid(const std::vector<Vec3d>& c, const std::vector<double>& r) : c_(c), r_(r) {
    lo_ = hi_ = c.front();
    double rsum = 0.0;
    for (std::size_t i = 0; i < c.size(); ++i) {
      for (int a = 0; a < 3; ++a) {
        lo_[a] = std::min(lo_[a], c[i][a]);
        hi_[a] = std::max(hi_[a], c[i][a]);
      }
      r_max_ = std::max(r_max_, r[i]);
      rsum += r[i];
    }
    // About two spheres per cell: cell edge from the box volume per sphere, at least the mean radius.
    const Vec3d e = hi_ - lo_;
    const double vol = std::max(e.x, 1e-9) * std::max(e.y, 1e-9) * std::max(e.z, 1e-9);
    cs_ = std::max(std::cbrt(2.0 * vol / double(c.size())), rsum / double(c.size()));
    cs_ = std::max(cs_, 1e-12 * (1.0 + norm(e)));
    for (int a = 0; a < 3; ++a) n_[a] = std::min(1024, int(std::floor(e[a] / cs_)) + 1);
    start_.assign(std::size_t(n_[0]) * n_[1] * n_[2] + 1, 0);
    std::vector<int> cell(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) ++start_[std::size_t(cell[i] = cellOf(c[i])) + 1];
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    items_.resize(c.size());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < c.size(); ++i) items_[std::size_t(fill[std::size_t(cell[i])]++)] = int(i);
  }

  // The `want` smallest (d_i, i) pairs, sorted ascending (fewer when there are fewer spheres).
  // With `allowed`, only spheres it accepts count (it is asked only for candidates that would enter the list).
  void nearest(const Vec3d& p, int want, std::vector<std::pair<double, int>>& best,
               const std::function<bool(int)>* allowed = nullptr) const {
    best.clear();
    int q[3];
    for (int a = 0; a < 3; ++a) q[a] = idx(p, a);
    // Distance from p to the grid box: shells start counting from the clamped cell.
    double outside = 0.0;
    for (int a = 0; a < 3; ++a) {
      const double gl = lo_[a], gh = lo_[a] + n_[a] * cs_;
      const double e = p[a] < gl ? gl - p[a] : (p[a] > gh ? p[a] - gh : 0.0);
      outside += e * e;
    }
    outside = std::sqrt(outside);
    const int max_shell = std::max({n_[0], n_[1], n_[2]});
    for (int m = 0; m <= max_shell; ++m) {
      for (int k = q[2] - m; k <= q[2] + m; ++k) {
        if (k < 0 || k >= n_[2]) continue;
        for (int j = q[1] - m; j <= q[1] + m; ++j) {
          if (j < 0 || j >= n_[1]) continue;
          for (int i = q[0] - m; i <= q[0] + m; ++i) {
            if (i < 0 || i >= n_[0]) continue;
            if (std::max({std::abs(i - q[0]), std::abs(j - q[1]), std::abs(k - q[2])}) != m) continue;  // shell only
            const std::size_t cidx = std::size_t((k * n_[1] + j) * n_[0] + i);
            for (int s = start_[cidx]; s < start_[cidx + 1]; ++s) {
              const int id = items_[std::size_t(s)];
              const std::pair<double, int> cand{norm(p - c_[std::size_t(id)]) - r_[std::size_t(id)], id};
              if (int(best.size()) == want && !(cand < best.back())) continue;
              if (allowed && !(*allowed)(id)) continue;
              if (int(best.size()) < want) {
                best.insert(std::upper_bound(best.begin(), best.end(), cand), cand);
              } else if (cand < best.back()) {
                best.pop_back();
                best.insert(std::upper_bound(best.begin(), best.end(), cand), cand);
              }
            }
          }
        }
      }
      // Every centre in shell m + 1 or beyond is at least max(outside, m * cs) from p (Chebyshev shells).
      if (int(best.size()) == want && std::max(outside, m * cs_) - r_max_ > best.back().first) break;
    }
  }

 private:
  int idx(const Vec3d& p, int a) const {
    return int(std::clamp(std::floor((p[a] - lo_[a]) / cs_), 0.0, double(n_[a] - 1)));
  }
  int cellOf(const Vec3d& p) const { return (idx(p, 2) * n_[1] + idx(p, 1)) * n_[0] + idx(p, 0); }
  const std::vector<Vec3d>& c_;
  const std::vector<double>& r_;
  Vec3d lo_, hi_;
  double cs_ = 1.0, r_max_ = 0.0;
  int n_[3] = {1, 1, 1};
  std::vector<int> start_, items_;
};

}  // namespace

SkinBinding bindSkin(const TriangleMesh& surface, const MetaballModel& mb, int k, const std::string& file) {
  return bindSkin(surface, mb, k, file, SkinFilter());
}

SkinBinding bindSkin(const TriangleMesh& surface, const MetaballModel& mb, int k, const std::string& file,
                     const SkinFilter& allowed) {
  if (k < 1 || k > 16)
    throw InputError(file, "skinning.k", "spheres per vertex must be in [1, 16], got " + std::to_string(k));
  if (mb.size() == 0) throw InputError(file, "skinning", "the metaball model has no spheres");
  if (mb.rest_radii.size() != mb.size()) throw InputError(file, "skinning", "radii and centres differ in count");
  for (std::size_t i = 0; i < mb.size(); ++i)
    if (!(mb.rest_radii[i] > 0.0) || !isFinite(mb.rest_centers[i]))
      throw InputError(file, "skinning.sphere " + std::to_string(i), "non-positive radius or non-finite centre");
  const int nv = int(surface.vertices.size());
  for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    for (int c : surface.triangles[t])
      if (c < 0 || c >= nv) throw InputError(file, "skinning.face " + std::to_string(t), "vertex index out of range");

  SkinBinding b;
  b.k = k;
  b.rest_vertices = surface.vertices;
  b.rest_centres = mb.rest_centers;
  b.sphere.assign(std::size_t(nv) * std::size_t(k), 0);
  b.weight.assign(std::size_t(nv) * std::size_t(k), 0.0);
  const CentreGrid grid(mb.rest_centers, mb.rest_radii);
  const int want = std::min<int>(k + 1, int(mb.size()));
  cpu::parallelFor(nv, [&](std::int64_t v) {
    thread_local std::vector<std::pair<double, int>> best;
    best.clear();
    if (allowed) {
      const std::function<bool(int)> sees = [&](int sphere) { return allowed(int(v), sphere); };
      grid.nearest(surface.vertices[std::size_t(v)], want, best, &sees);
    }
    if (best.empty()) grid.nearest(surface.vertices[std::size_t(v)], want, best);  // unfiltered, or none allowed
    const double dmin = best.front().first;
    // rho: the first unbound sphere; with no such sphere, 1.5 x the farthest bound one (its weight stays > 0).
    double rho = int(best.size()) > k ? best[std::size_t(k)].first - dmin : 1.5 * (best.back().first - dmin);
    const int used = std::min<int>(k, int(best.size()));
    double wsum = 0.0;
    double w[16];
    for (int j = 0; j < used; ++j) wsum += (w[j] = skin::bindWeight(best[std::size_t(j)].first - dmin, rho));
    for (int j = 0; j < k; ++j) {
      const std::size_t slot = std::size_t(v) * std::size_t(k) + std::size_t(j);
      b.sphere[slot] = best[std::size_t(std::min(j, used - 1))].second;
      b.weight[slot] = j < used ? w[j] / wsum : 0.0;
    }
  });

  b.triangles.reserve(surface.triangles.size() * 3);
  b.tri_offsets.assign(std::size_t(nv) + 1, 0);
  for (const auto& t : surface.triangles)
    for (int c : t) {
      b.triangles.push_back(c);
      ++b.tri_offsets[std::size_t(c) + 1];
    }
  std::partial_sum(b.tri_offsets.begin(), b.tri_offsets.end(), b.tri_offsets.begin());
  b.tri_of_vertex.resize(std::size_t(b.tri_offsets.back()));
  std::vector<std::int32_t> fill(b.tri_offsets.begin(), b.tri_offsets.end() - 1);
  for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    for (int c : surface.triangles[t]) b.tri_of_vertex[std::size_t(fill[std::size_t(c)]++)] = std::int32_t(t);
  return b;
}

template <typename T>
SkinArrays<T> skinArrays(const SkinBinding& b) {
  SkinArrays<T> a;
  a.k = b.k;
  for (const auto& p : b.rest_vertices) a.rest_vertices.push_back(Vec3<T>(p));
  for (const auto& p : b.rest_centres) a.rest_centres.push_back(Vec3<T>(p));
  a.sphere = b.sphere;
  a.weight.resize(b.weight.size());
  // Renormalise in T so that the weights sum to 1 to the precision of T (the rigid-motion property).
  for (std::size_t v = 0; v < b.rest_vertices.size(); ++v) {
    T sum = T(0);
    for (int j = 0; j < b.k; ++j)
      sum += (a.weight[v * std::size_t(b.k) + std::size_t(j)] = T(b.weight[v * std::size_t(b.k) + std::size_t(j)]));
    for (int j = 0; j < b.k; ++j) a.weight[v * std::size_t(b.k) + std::size_t(j)] /= sum;
  }
  a.triangles = b.triangles;
  a.tri_offsets = b.tri_offsets;
  a.tri_of_vertex = b.tri_of_vertex;
  return a;
}

template <typename T>
SphereNeighbourhoods<T> sphereNeighbourhoods(const MetaballModel& mb) {
  const int n = int(mb.size());
  if (mb.masses.size() != mb.size()) throw InputError("metaball model", "masses", "one mass per sphere needed");
  SphereNeighbourhoods<T> h;
  h.offsets.assign(std::size_t(n) + 1, 0);
  for (const auto& l : mb.links) {
    if (l[0] < 0 || l[1] < 0 || l[0] >= n || l[1] >= n || l[0] == l[1])
      throw InputError("metaball model", "links",
                       "link (" + std::to_string(l[0]) + ", " + std::to_string(l[1]) + ") out of range");
    ++h.offsets[std::size_t(l[0]) + 1];
    ++h.offsets[std::size_t(l[1]) + 1];
  }
  std::partial_sum(h.offsets.begin(), h.offsets.end(), h.offsets.begin());
  h.neighbours.resize(std::size_t(h.offsets.back()));
  std::vector<std::int32_t> fill(h.offsets.begin(), h.offsets.end() - 1);
  for (const auto& l : mb.links) {
    h.neighbours[std::size_t(fill[std::size_t(l[0])]++)] = l[1];
    h.neighbours[std::size_t(fill[std::size_t(l[1])]++)] = l[0];
  }
  for (int i = 0; i < n; ++i)
    std::sort(h.neighbours.begin() + h.offsets[std::size_t(i)], h.neighbours.begin() + h.offsets[std::size_t(i) + 1]);
  for (double m : mb.masses) h.masses.push_back(T(m));
  for (const auto& c : mb.rest_centers) h.rest_centres.push_back(Vec3<T>(c));
  return h;
}

template SphereNeighbourhoods<float> sphereNeighbourhoods<float>(const MetaballModel&);
template SphereNeighbourhoods<double> sphereNeighbourhoods<double>(const MetaballModel&);
template SkinArrays<float> skinArrays<float>(const SkinBinding&);
template SkinArrays<double> skinArrays<double>(const SkinBinding&);

}  // namespace inc
