// analyzeMesh and requireClosedMesh: edge topology, orientation, components, volume, area; inward meshes flipped.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "base/format_number.h"
#include "host/io/edge_order.h"
#include "host/io/mesh.h"
#include "model/input_error.h"

namespace inc {

namespace {

// A triangle is degenerate when its height over the longest edge is below this fraction of that edge: its
// area is zero to within double rounding of the coordinates.
constexpr double kDegenerateRelHeight = 1e-10;

struct Example {
  int a = -1, b = -1;  // vertex indices of one edge of the category, or -1
};

struct EdgeFacts {
  int boundary = 0, non_manifold = 0, inconsistent = 0;
  Example boundary_ex, non_manifold_ex, inconsistent_ex;
};

bool validTriangle(const std::array<int, 3>& t, int n) {
  for (int v : t)
    if (v < 0 || v >= n) return false;
  return t[0] != t[1] && t[1] != t[2] && t[2] != t[0];
}

EdgeFacts classifyEdges(const TriangleMesh& mesh) {
  struct Directed {
    int lo, hi;  // undirected key
    int from;    // the direction the triangle walks it: from -> other
  };
  const int n = static_cast<int>(mesh.vertices.size());
  std::vector<Directed> edges;
  edges.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles) {
    if (!validTriangle(t, n)) continue;  // repeated or bad indices: counted as degenerate, no edges
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      edges.push_back({std::min(a, b), std::max(a, b), a});
    }
  }
  // Ordered by (lo, hi, from).
  sortByLowerVertex(edges, std::size_t(n),
                    [](const Directed& x, const Directed& y) { return x.hi != y.hi ? x.hi < y.hi : x.from < y.from; });
  EdgeFacts f;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    const std::size_t uses = j - i;
    const Example ex{edges[i].lo, edges[i].hi};
    if (uses == 1) {
      if (f.boundary++ == 0) f.boundary_ex = ex;
    } else if (uses > 2) {
      if (f.non_manifold++ == 0) f.non_manifold_ex = ex;
    } else if (edges[i].from == edges[i + 1].from) {
      // Two triangles walking the shared edge the same way face opposite sides of the surface.
      if (f.inconsistent++ == 0) f.inconsistent_ex = ex;
    }
    i = j;
  }
  return f;
}

// Union-find over vertices, joined along the triangles' corners.
struct Components {
  explicit Components(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  }
  void join(int a, int b) { parent[find(a)] = find(b); }
  std::vector<int> parent;
};

// Component label (0..count-1) per triangle; -1 for triangles with out-of-range indices.
std::vector<int> triangleComponents(const TriangleMesh& mesh, int& count) {
  const int n = static_cast<int>(mesh.vertices.size());
  Components uf(n);
  auto in_range = [n](const std::array<int, 3>& t) {
    return t[0] >= 0 && t[0] < n && t[1] >= 0 && t[1] < n && t[2] >= 0 && t[2] < n;
  };
  for (const auto& t : mesh.triangles) {
    if (!in_range(t)) continue;
    uf.join(t[0], t[1]);
    uf.join(t[1], t[2]);
  }
  std::vector<int> label(n, -1), tri(mesh.triangles.size(), -1);
  count = 0;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    if (!in_range(mesh.triangles[i])) continue;
    const int r = uf.find(mesh.triangles[i][0]);
    if (label[r] < 0) label[r] = count++;
    tri[i] = label[r];
  }
  return tri;
}

Vec3d bboxCenter(const TriangleMesh& mesh) {
  if (mesh.vertices.empty()) return Vec3d();
  Vec3d lo = mesh.vertices[0], hi = mesh.vertices[0];
  for (const Vec3d& p : mesh.vertices) {
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], p[c]);
      hi[c] = std::max(hi[c], p[c]);
    }
  }
  return 0.5 * (lo + hi);
}

std::string edgeText(const TriangleMesh& mesh, const Example& e) {
  const Vec3d m = 0.5 * (mesh.vertices[e.a] + mesh.vertices[e.b]);
  return "e.g. the edge between vertices " + std::to_string(e.a) + " and " + std::to_string(e.b) + " near (" +
         formatNumber(m.x) + ", " + formatNumber(m.y) + ", " + formatNumber(m.z) + ")";
}

}  // namespace

MeshReport analyzeMesh(const TriangleMesh& mesh) {
  MeshReport r;
  r.vertex_count = static_cast<int>(mesh.vertices.size());
  r.triangle_count = static_cast<int>(mesh.triangles.size());
  if (!mesh.vertices.empty()) {
    r.bbox_min = r.bbox_max = mesh.vertices[0];
    for (const Vec3d& p : mesh.vertices) {
      for (int c = 0; c < 3; ++c) {
        r.bbox_min[c] = std::min(r.bbox_min[c], p[c]);
        r.bbox_max[c] = std::max(r.bbox_max[c], p[c]);
      }
    }
  }
  const EdgeFacts f = classifyEdges(mesh);
  r.boundary_edges = f.boundary;
  r.non_manifold_edges = f.non_manifold;
  r.inconsistent_edges = f.inconsistent;
  triangleComponents(mesh, r.components);

  // Volume by the divergence theorem about the box centre (smaller rounding than about the origin).
  const Vec3d o = bboxCenter(mesh);
  const int n = r.vertex_count;
  double vol6 = 0.0, area2 = 0.0;
  for (const auto& t : mesh.triangles) {
    bool in_range = true;
    for (int v : t) in_range = in_range && v >= 0 && v < n;
    if (!in_range) {
      ++r.degenerate_triangles;
      continue;
    }
    const Vec3d a = mesh.vertices[t[0]] - o, b = mesh.vertices[t[1]] - o, c = mesh.vertices[t[2]] - o;
    const Vec3d cr = cross(b - a, c - a);
    const double twice_area = norm(cr);
    const double longest2 = std::max({norm2(b - a), norm2(c - b), norm2(a - c)});
    // height = twice_area / longest; degenerate when height <= k * longest.
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0] || twice_area <= kDegenerateRelHeight * longest2) {
      ++r.degenerate_triangles;
    }
    vol6 += dot(a, cross(b, c));
    area2 += twice_area;
  }
  r.signed_volume = vol6 / 6.0;
  r.area = area2 / 2.0;
  return r;
}

std::string requireClosedMesh(TriangleMesh& mesh, const std::string& file, const std::string& key) {
  if (mesh.vertices.empty() || mesh.triangles.empty()) throw InputError(file, key, "empty mesh: no triangles");
  const int n = static_cast<int>(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int v : mesh.triangles[t]) {
      if (v < 0 || v >= n)
        throw InputError(file, key,
                         "triangle " + std::to_string(t) + " has vertex index " + std::to_string(v) +
                             " out of range (the mesh has " + std::to_string(n) + " vertices)");
    }
  }
  const EdgeFacts f = classifyEdges(mesh);
  std::string problems;
  auto add = [&problems](const std::string& s) { problems += (problems.empty() ? "" : "; ") + s; };
  if (f.boundary > 0) {
    add("the mesh is open: " + std::to_string(f.boundary) + " boundary edges (holes), " +
        edgeText(mesh, f.boundary_ex));
  }
  if (f.non_manifold > 0) {
    add(std::to_string(f.non_manifold) + " non-manifold edges shared by more than two triangles, " +
        edgeText(mesh, f.non_manifold_ex));
  }
  if (f.inconsistent > 0) {
    add("inconsistently oriented: " + std::to_string(f.inconsistent) +
        " edges walked the same way by both of their triangles, " + edgeText(mesh, f.inconsistent_ex));
  }
  if (!problems.empty())
    throw InputError(file, key, "a closed, manifold, consistently oriented surface is needed: " + problems);

  // Per component: a closed, consistently oriented shell has a signed volume whose sign says its orientation.
  int count = 0;
  const std::vector<int> comp = triangleComponents(mesh, count);
  const Vec3d o = bboxCenter(mesh);
  std::vector<double> vol(count, 0.0);
  std::vector<Vec3d> lo(count, Vec3d(1e300, 1e300, 1e300)), hi(count, Vec3d(-1e300, -1e300, -1e300));
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t = mesh.triangles[i];
    const Vec3d a = mesh.vertices[t[0]] - o, b = mesh.vertices[t[1]] - o, c = mesh.vertices[t[2]] - o;
    vol[comp[i]] += dot(a, cross(b, c)) / 6.0;
    for (int k = 0; k < 3; ++k) {
      const Vec3d& p = mesh.vertices[t[k]];
      for (int d = 0; d < 3; ++d) {
        lo[comp[i]][d] = std::min(lo[comp[i]][d], p[d]);
        hi[comp[i]][d] = std::max(hi[comp[i]][d], p[d]);
      }
    }
  }
  std::vector<bool> flip(count, false);
  int flipped_components = 0;
  for (int c = 0; c < count; ++c) {
    const double diag = norm(hi[c] - lo[c]);
    if (std::fabs(vol[c]) <= 1e-9 * diag * diag * diag) {
      throw InputError(file, key,
                       "component " + std::to_string(c) + " of the mesh encloses no volume (signed volume " +
                           formatNumber(vol[c]) + ", a flat or doubled-over surface)");
    }
    if (vol[c] > 0) continue;
    // An inward shell strictly inside an outward one is a cavity and is right as it is.
    bool cavity = false;
    for (int p = 0; p < count && !cavity; ++p) {
      if (p == c || vol[p] <= 0) continue;
      cavity = lo[p].x < lo[c].x && lo[p].y < lo[c].y && lo[p].z < lo[c].z && hi[c].x < hi[p].x && hi[c].y < hi[p].y &&
               hi[c].z < hi[p].z;
    }
    if (!cavity) {
      flip[c] = true;
      ++flipped_components;
    }
  }
  const double before = std::accumulate(vol.begin(), vol.end(), 0.0);
  std::string note;
  if (flipped_components > 0) {
    std::size_t flipped_triangles = 0;
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
      if (!flip[comp[i]]) continue;
      std::swap(mesh.triangles[i][1], mesh.triangles[i][2]);
      ++flipped_triangles;
    }
    double after = 0.0;
    for (int c = 0; c < count; ++c) after += flip[c] ? -vol[c] : vol[c];
    note = "the mesh was oriented inward: flipped " + std::to_string(flipped_triangles) + " triangles in " +
           std::to_string(flipped_components) + " of " + std::to_string(count) +
           " components to face outward (signed volume " + formatNumber(before) + " -> " + formatNumber(after) + ")";
    if (!(after > 0)) throw InputError(file, key, "the mesh encloses no positive volume even after reorienting it");
  } else if (!(before > 0)) {
    throw InputError(file, key, "the mesh encloses no positive volume (signed volume " + formatNumber(before) + ")");
  }
  return note;
}

}  // namespace inc
