// Surface split along a swept surface: crossings, triangle pieces, contour chains and slits, walls, checks.
#include "host/cut/cut_surface_split.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numeric>
#include <string>
#include <utility>

#include "host/cut/cut_sweep_domain.h"
#include "host/cut/cut_wall_cdt.h"
#include "host/io/edge_order.h"
#include "model/input_error.h"

namespace inc {

double triangleArea(const Vec3d& a, const Vec3d& b, const Vec3d& c) { return 0.5 * norm(cross(b - a, c - a)); }

double triangleMinAngleDeg(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const auto angle = [](const Vec3d& p, const Vec3d& q, const Vec3d& r) {  // at p
    const Vec3d u = q - p, v = r - p;
    return std::atan2(norm(cross(u, v)), dot(u, v));
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)}) * 180.0 / 3.14159265358979323846;
}

int nonManifoldVertexCount(const TriangleMesh& m) {
  // Around vertex v each incident triangle (v, b, c) contributes the link edge b -> c; a closed manifold vertex
  // has links forming exactly one cycle.
  std::vector<std::vector<std::pair<int, int>>> links(m.vertices.size());
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) links[std::size_t(t[k])].push_back({t[(k + 1) % 3], t[(k + 2) % 3]});
  int bad = 0;
  for (auto& l : links) {
    if (l.empty()) continue;
    std::sort(l.begin(), l.end());
    bool ok = true;
    for (std::size_t i = 1; i < l.size() && ok; ++i) ok = l[i].first != l[i - 1].first;
    std::size_t steps = 0;
    int cur = l.front().first;
    while (ok) {
      const auto it = std::lower_bound(l.begin(), l.end(), std::pair<int, int>{cur, std::numeric_limits<int>::min()});
      if (it == l.end() || it->first != cur) {
        ok = false;
        break;
      }
      cur = it->second;
      ++steps;
      if (cur == l.front().first || steps > l.size()) break;
    }
    if (!ok || steps != l.size() || cur != l.front().first) ++bad;
  }
  return bad;
}

namespace {

constexpr double kPi = 3.14159265358979323846;

struct EdgeCrossing {
  bool cross = false, real = false;
  Vec3d x;
  Vec2d uv{0.0, 0.0};
  int node = -1;
};

enum class NodeKind { Crossing, OnVertex, Pierce, Front };  // Crossing and OnVertex: one copy per side

struct Node {
  NodeKind kind;
  Vec3d x;
  Vec2d uv;
  int v_plus = -1, v_minus = -1;  // output vertices (equal for Pierce and Front)
  double s = 0.0;                 // outline position (Pierce, Front)
  int vertex = -1;                // OnVertex: the input vertex (its index is the + copy)
};

// Segment [p, q] against triangle (a, b, c): parameter t of the hit (barycentric bounds widened by 1e-9 so a
// segment through an edge shared by two strip triangles hits one of them, as segmentCrossesTriangle).
bool segmentHit(const Vec3d& p, const Vec3d& q, const Vec3d& a, const Vec3d& b, const Vec3d& c, double& t) {
  const Vec3d d = q - p, e1 = b - a, e2 = c - a, h = cross(d, e2);
  const double det = dot(e1, h);
  if (!(std::fabs(det) > 1e-12 * norm(e1) * norm(e2) * norm(d))) return false;
  const double inv = 1.0 / det;
  const Vec3d s = p - a;
  const double u = dot(s, h) * inv;
  if (u < -1e-9 || u > 1.0 + 1e-9) return false;
  const Vec3d qv = cross(s, e1);
  const double v = dot(d, qv) * inv;
  if (v < -1e-9 || u + v > 1.0 + 1e-9) return false;
  t = dot(e2, qv) * inv;
  return t >= 0.0 && t <= 1.0;
}

bool lexLess(const Vec3d& a, const Vec3d& b) { return a.x != b.x ? a.x < b.x : (a.y != b.y ? a.y < b.y : a.z < b.z); }

// Generalised winding number of a closed oriented mesh at p (1 inside, 0 outside), by solid angles.
double windingNumber(const TriangleMesh& m, const Vec3d& p) {
  double sum = 0.0;
  for (const auto& t : m.triangles) {
    const Vec3d a = m.vertices[t[0]] - p, b = m.vertices[t[1]] - p, c = m.vertices[t[2]] - p;
    const double la = norm(a), lb = norm(b), lc = norm(c);
    const double num = dot(a, cross(b, c));
    const double den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
    sum += 2.0 * std::atan2(num, den);
  }
  return sum / (4.0 * kPi);
}

void checkInputMesh(const TriangleMesh& mesh) {
  const int n = int(mesh.vertices.size());
  if (mesh.triangles.empty()) throw InputError("cut", "surface mesh", "has no triangles");
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int v : mesh.triangles[t])
      if (v < 0 || v >= n)
        throw InputError("cut", "surface mesh", "triangle " + std::to_string(t) + " has a vertex index out of range");
  for (int i = 0; i < n; ++i)
    if (!isFinite(mesh.vertices[std::size_t(i)]))
      throw InputError("cut", "surface mesh", "vertex " + std::to_string(i) + " is not finite");
  const MeshReport r = analyzeMesh(mesh);
  if (r.boundary_edges > 0)
    throw InputError("cut", "surface mesh", "not closed: " + std::to_string(r.boundary_edges) + " boundary edges");
  if (r.non_manifold_edges > 0)
    throw InputError("cut", "surface mesh",
                     "not manifold: " + std::to_string(r.non_manifold_edges) + " edges with more than two triangles");
  if (r.inconsistent_edges > 0)
    throw InputError("cut", "surface mesh",
                     "inconsistently oriented: " + std::to_string(r.inconsistent_edges) + " edges");
  if (r.degenerate_triangles > 0)
    throw InputError("cut", "surface mesh", std::to_string(r.degenerate_triangles) + " degenerate triangles");
  const int pinched = nonManifoldVertexCount(mesh);
  if (pinched > 0) throw InputError("cut", "surface mesh", "not manifold at " + std::to_string(pinched) + " vertices");
}

class Splitter {
 public:
  Splitter(const TriangleMesh& mesh, const SweptSurface& sweep, const SurfaceSplitOptions& opt)
      : m_(mesh), s_(sweep), opt_(opt), dom_(unfoldSweptSurface(sweep)), query_(sweep) {
    Vec3d lo = mesh.vertices.front(), hi = lo;
    for (const auto& v : mesh.vertices)
      for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
    size_ = norm(hi - lo);
    probe_eps_ = 1e-6 * size_;
  }

  SurfaceSplit run() {
    buildEdges();
    classifyVertices();
    computeCrossings();
    SurfaceSplit out;
    int real = 0;
    for (const auto& e : edge_x_) real += e.real;
    for (int sd : side_) real += sd == 0;
    if (real == 0) {  // the blade crosses no mesh edge and meets no vertex: nothing of the surface is cut
      out.mesh = m_;
      out.vertex_side.resize(m_.vertices.size());
      for (std::size_t v = 0; v < m_.vertices.size(); ++v)
        out.vertex_side[v] = std::int8_t(
            !far_[v] ? side_[v] : (projectOntoSweep(s_, dom_, query_, m_.vertices[v]).offset >= 0.0 ? 1 : -1));
      out.binding_probe = m_.vertices;
      out.source_triangle.resize(m_.triangles.size());
      std::iota(out.source_triangle.begin(), out.source_triangle.end(), 0);
      out.wall.assign(m_.triangles.size(), 0);
      out.components = analyzeMesh(m_).components;
      return out;
    }
    splitTriangles();
    buildLoops();
    triangulateWalls();
    return assemble();
  }

 private:
  void buildEdges() {
    struct Half {
      int lo, hi, slot;
    };
    std::vector<Half> h;
    h.reserve(m_.triangles.size() * 3);
    for (std::size_t t = 0; t < m_.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int a = m_.triangles[t][k], b = m_.triangles[t][(k + 1) % 3];
        h.push_back({std::min(a, b), std::max(a, b), int(t * 3 + std::size_t(k))});
      }
    // Ordered by (lo, hi, slot): the two halves of an edge in a defined order.
    sortByLowerVertex(h, m_.vertices.size(),
                      [](const Half& x, const Half& y) { return x.hi != y.hi ? x.hi < y.hi : x.slot < y.slot; });
    tri_edge_.assign(m_.triangles.size() * 3, -1);
    for (std::size_t i = 0; i < h.size(); ++i) {
      if (i == 0 || h[i].lo != h[i - 1].lo || h[i].hi != h[i - 1].hi) {
        edges_.push_back({h[i].lo, h[i].hi});
        edge_tris_.push_back({-1, -1});
      }
      tri_edge_[std::size_t(h[i].slot)] = int(edges_.size()) - 1;
      auto& et = edge_tris_.back();
      (et[0] < 0 ? et[0] : et[1]) = h[i].slot / 3;
    }
    vertex_node_.assign(m_.vertices.size(), -1);
  }

  // Vertex labels: +1 / -1, the sign of the offset from the plane of the closest swept triangle (0 counts as +,
  // the convention of sideOfSweptSurface), or 0 for a vertex snapped onto the cut. One label per vertex makes
  // the crossing consistent whatever the rounding. Snap: a vertex whose crossing on some edge would lie within
  // snap_fraction of it is put on the cut (the crossing curve passes through the vertex, which is duplicated)
  // when it lies over the strip, the labels around it form one + run and one - run, and no triangle gets three
  // snapped corners; otherwise it takes the side of the majority of its neighbours. Either way no crossing lies
  // closer than snap_fraction of an edge to a vertex, and a blade that only grazes a vertex or lies on a face
  // cuts nothing. Coincident vertices (the two walls of an earlier cut) are decided together, so the crossing
  // curves on coincident walls coincide.
  void classifyVertices() {
    side_.resize(m_.vertices.size());
    proj_.resize(m_.vertices.size());
    VertexSnap snap;
    snap.vertex_normal = outwardVertexNormals();
    const double longest = measureEdges(snap.shortest);
    labelVertices(snap, longest);
    groupCoincidentVertices(snap);
    findSnapCandidates(snap);
    settleSnaps(snap);
  }

  // classifyVertices' working state, phase to phase.
  struct VertexSnap {
    std::vector<Vec3d> vertex_normal;      // outward, area-weighted
    std::vector<double> shortest;          // per vertex: its shortest edge
    std::vector<std::vector<int>> groups;  // coincident vertices
    std::vector<int> group_of;
    std::vector<char> cand;           // per group: a snap candidate
    std::vector<char> ok_over_strip;  // per candidate group: lies over the strip, away from its outline
    std::vector<std::vector<std::pair<int, int>>> links;  // umbrella rings (neighbours in cyclic order)
  };

  // Outward (area-weighted) vertex normals: a vertex lying on the swept surface takes the side of the
  // material below the mesh there, so a blade lying on a face cuts nothing.
  std::vector<Vec3d> outwardVertexNormals() const {
    std::vector<Vec3d> vertex_normal(m_.vertices.size());
    for (const auto& t : m_.triangles) {
      const Vec3d n = cross(m_.vertices[std::size_t(t[1])] - m_.vertices[std::size_t(t[0])],
                            m_.vertices[std::size_t(t[2])] - m_.vertices[std::size_t(t[0])]);
      for (int v : t) vertex_normal[std::size_t(v)] += n;
    }
    return vertex_normal;
  }

  int materialSide(const VertexSnap& snap, int v, double fallback) const {
    const double facing = dot(snap.vertex_normal[std::size_t(v)], proj_[std::size_t(v)].normal);
    return facing > 0.0 ? -1 : (facing < 0.0 ? 1 : (fallback >= 0.0 ? 1 : -1));
  }

  // Each vertex's shortest edge and neighbours (adj_); returns the longest edge.
  double measureEdges(std::vector<double>& shortest) {
    const std::size_t nv = m_.vertices.size();
    shortest.assign(nv, std::numeric_limits<double>::infinity());
    adj_.assign(nv, {});
    double longest = 0.0;
    for (const auto& e : edges_) {
      const double l = norm(m_.vertices[std::size_t(e[0])] - m_.vertices[std::size_t(e[1])]);
      longest = std::max(longest, l);
      for (int k = 0; k < 2; ++k) {
        shortest[std::size_t(e[k])] = std::min(shortest[std::size_t(e[k])], l);
        adj_[std::size_t(e[k])].push_back(e[1 - k]);
      }
    }
    return longest;
  }

  // The first labels: the side of each vertex's projection onto the sweep (a vertex on it: the material side).
  // Vertices farther than two edges from the strip's box take no part in any crossing or snap (an edge that
  // meets the strip has both ends within one edge of it): they are labelled later, only if needed.
  void labelVertices(const VertexSnap& snap, double longest) {
    const std::size_t nv = m_.vertices.size();
    far_.assign(nv, 0);
    for (std::size_t v = 0; v < nv; ++v) {
      const Vec3d& x = m_.vertices[v];
      double out2 = 0.0;
      for (int a = 0; a < 3; ++a) {
        const double o = std::max({dom_.box_lo[a] - x[a], x[a] - dom_.box_hi[a], 0.0});
        out2 += o * o;
      }
      if (out2 > 4.0 * longest * longest) {
        far_[v] = 1;
        side_[v] = 1;
        proj_[v].offset = std::numeric_limits<double>::max();
        continue;
      }
      proj_[v] = projectOntoSweep(s_, dom_, query_, x);
      side_[v] = std::fabs(proj_[v].offset) <= 1e-12 * size_ ? materialSide(snap, int(v), proj_[v].offset)
                                                             : (proj_[v].offset >= 0.0 ? 1 : -1);
    }
  }

  // Groups of coincident vertices.
  void groupCoincidentVertices(VertexSnap& snap) const {
    const std::size_t nv = m_.vertices.size();
    std::vector<int> order(nv);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      return lexLess(m_.vertices[std::size_t(a)], m_.vertices[std::size_t(b)]) ||
             (!lexLess(m_.vertices[std::size_t(b)], m_.vertices[std::size_t(a)]) && a < b);
    });
    for (std::size_t i = 0; i < nv;) {
      std::size_t j = i + 1;
      while (j < nv && norm2(m_.vertices[std::size_t(order[j])] - m_.vertices[std::size_t(order[i])]) == 0.0) ++j;
      snap.groups.emplace_back(order.begin() + std::ptrdiff_t(i), order.begin() + std::ptrdiff_t(j));
      i = j;
    }
    snap.group_of.resize(nv);
    for (std::size_t g = 0; g < snap.groups.size(); ++g)
      for (int v : snap.groups[g]) snap.group_of[std::size_t(v)] = int(g);
  }

  // Candidates: some crossing within snap_fraction of the vertex; and whether each lies over the strip.
  void findSnapCandidates(VertexSnap& snap) const {
    const double tau = opt_.snap_fraction;
    snap.cand.assign(snap.groups.size(), 0);
    for (std::size_t g = 0; g < snap.groups.size(); ++g)
      for (int v : snap.groups[g])
        for (int w : adj_[std::size_t(v)]) {
          if (side_[std::size_t(v)] == side_[std::size_t(w)] || far_[std::size_t(v)] || far_[std::size_t(w)]) continue;
          const double a = std::fabs(proj_[std::size_t(v)].offset), b = std::fabs(proj_[std::size_t(w)].offset);
          if (a < tau * (a + b)) snap.cand[g] = 1;
        }
    // Umbrella rings (neighbours in cyclic order) for the one-run-each check.
    snap.links.resize(m_.vertices.size());
    for (const auto& t : m_.triangles)
      for (int k = 0; k < 3; ++k) snap.links[std::size_t(t[k])].push_back({t[(k + 1) % 3], t[(k + 2) % 3]});
    const auto outlineDistance = [&](const Vec2d& uv) {
      const Vec2d q = outlinePoint(dom_, outlinePosition(dom_, uv));
      return std::hypot(q[0] - uv[0], q[1] - uv[1]);
    };
    snap.ok_over_strip.assign(snap.groups.size(), 0);
    for (std::size_t g = 0; g < snap.groups.size(); ++g) {
      if (!snap.cand[g]) continue;
      const int v = snap.groups[g].front();
      snap.ok_over_strip[g] = insideOutline(dom_, proj_[std::size_t(v)].uv) &&
                              outlineDistance(proj_[std::size_t(v)].uv) > 0.5 * snap.shortest[std::size_t(v)];
    }
  }

  // Whether the labels around v (its umbrella ring in cyclic order) form one + run and one - run.
  bool twoRuns(VertexSnap& snap, int v) const {
    auto& l = snap.links[std::size_t(v)];
    std::sort(l.begin(), l.end());
    std::vector<int> ring;
    int cur = l.front().first;
    for (std::size_t k = 0; k < l.size(); ++k) {
      ring.push_back(cur);
      const auto it = std::lower_bound(l.begin(), l.end(), std::pair<int, int>{cur, std::numeric_limits<int>::min()});
      cur = it->second;
    }
    std::vector<int> signs;
    for (int w : ring)
      if (side_[std::size_t(w)] != 0) signs.push_back(side_[std::size_t(w)]);
    int changes = 0;
    for (std::size_t k = 0; k < signs.size(); ++k) changes += signs[k] != signs[(k + 1) % signs.size()];
    return changes == 2;
  }

  // Released: the majority side of the neighbours; with none decided, the material side.
  void unsnap(VertexSnap& snap, std::size_t g) {
    snap.cand[g] = 0;
    int vote = 0;
    for (int v : snap.groups[g])
      for (int w : adj_[std::size_t(v)]) vote += side_[std::size_t(w)];
    const int own = materialSide(snap, snap.groups[g].front(), proj_[std::size_t(snap.groups[g].front())].offset);
    for (int v : snap.groups[g]) side_[std::size_t(v)] = vote > 0 ? 1 : (vote < 0 ? -1 : own);
  }

  // The candidates snap onto the cut; those that would leave a triangle of three snapped corners (the farthest
  // corner goes), lie off the strip or break the one-run-each rule are released, until nothing changes.
  void settleSnaps(VertexSnap& snap) {
    const auto offset = [&](int v) { return proj_[std::size_t(v)].offset; };
    for (int round = 0; round < 16; ++round) {
      for (std::size_t g = 0; g < snap.groups.size(); ++g)
        if (snap.cand[g])
          for (int v : snap.groups[g]) side_[std::size_t(v)] = 0;
      bool changed = false;
      for (const auto& t : m_.triangles) {
        if (side_[std::size_t(t[0])] != 0 || side_[std::size_t(t[1])] != 0 || side_[std::size_t(t[2])] != 0) continue;
        int far = t[0];  // a triangle of three snapped corners would lie in the cut: release the farthest one
        for (int v : t)
          if (std::fabs(offset(v)) > std::fabs(offset(far)) ||
              (std::fabs(offset(v)) == std::fabs(offset(far)) && v > far))
            far = v;
        unsnap(snap, std::size_t(snap.group_of[std::size_t(far)]));
        changed = true;
      }
      for (std::size_t g = 0; g < snap.groups.size(); ++g) {
        if (!snap.cand[g]) continue;
        bool ok = snap.ok_over_strip[g];
        for (int v : snap.groups[g]) ok = ok && twoRuns(snap, v);
        if (!ok) {
          unsnap(snap, g);
          changed = true;
        }
      }
      if (!changed) break;
      if (round == 15) throw CutInconsistent("vertex snapping did not settle");
    }
  }

  // Each edge whose ends carry opposite labels crosses the surface or its extension; the crossing is real when
  // the segment meets the swept strip itself (or, where snapping flipped an end's label, when the crossing lies
  // over the strip). Computed from the end points in lexicographic order so that coincident edges (two walls of
  // an earlier cut) give bit-identical crossings. The domain position is that of the exact hit on the strip, so
  // the crossing curve maps to the domain in order; the 3D point is kept snap_fraction away from the ends.
  void computeCrossings() {
    const double tau = opt_.snap_fraction;
    edge_x_.assign(edges_.size(), EdgeCrossing{});
    for (std::size_t e = 0; e < edges_.size(); ++e) {
      int a = edges_[e][0], b = edges_[e][1];
      if (side_[std::size_t(a)] * side_[std::size_t(b)] != -1) continue;
      if (far_[std::size_t(a)] || far_[std::size_t(b)]) {  // cannot meet the strip, and no cut triangle uses it
        edge_x_[e].cross = true;
        continue;
      }
      if (lexLess(m_.vertices[std::size_t(b)], m_.vertices[std::size_t(a)])) std::swap(a, b);
      const Vec3d &p = m_.vertices[std::size_t(a)], &q = m_.vertices[std::size_t(b)];
      const double oa = proj_[std::size_t(a)].offset, ob = proj_[std::size_t(b)].offset;
      const bool geometric = (oa >= 0.0) != (ob >= 0.0);
      const double t0 = geometric ? oa / (oa - ob) : 0.5;
      double t = t0, best = std::numeric_limits<double>::infinity();
      bool hit = false;
      for (const auto& tri : s_.triangles) {
        const Vec3d &A = s_.vertices[tri[0]], &B = s_.vertices[tri[1]], &C = s_.vertices[tri[2]];
        bool apart = false;
        for (int k = 0; k < 3 && !apart; ++k) {
          const double lo = std::min({A[k], B[k], C[k]}), hi = std::max({A[k], B[k], C[k]});
          const double mg = 1e-6 * (hi - lo) + 1e-12;
          apart = std::max(p[k], q[k]) < lo - mg || std::min(p[k], q[k]) > hi + mg;
        }
        double th;
        if (!apart && segmentHit(p, q, A, B, C, th) && std::fabs(th - t0) < best) {
          best = std::fabs(th - t0);
          t = th;
          hit = true;
        }
      }
      EdgeCrossing& x = edge_x_[e];
      x.cross = true;
      x.uv = projectOntoSweep(s_, dom_, query_, p + (q - p) * t).uv;
      x.real = hit || (!geometric && insideOutline(dom_, x.uv));
      x.x = p + (q - p) * std::clamp(t, tau, 1.0 - tau);
    }
  }

  int crossingNode(int e) {
    EdgeCrossing& x = edge_x_[std::size_t(e)];
    if (x.node < 0) {
      x.node = int(nodes_.size());
      nodes_.push_back({NodeKind::Crossing, x.x, x.uv});
    }
    return x.node;
  }

  int vertexNode(int v) {
    int& id = vertex_node_[std::size_t(v)];
    if (id < 0) {
      id = int(nodes_.size());
      nodes_.push_back({NodeKind::OnVertex, m_.vertices[std::size_t(v)], proj_[std::size_t(v)].uv});
      nodes_.back().vertex = v;
    }
    return id;
  }

  int pierceNode(const Vec3d& x) {
    const int p = int(nodes_.size());
    nodes_.push_back({NodeKind::Pierce, x, projectOntoSweep(s_, dom_, query_, x).uv});
    nodes_.back().s = outlinePosition(dom_, nodes_.back().uv);
    pierces_.push_back(p);
    return p;
  }

  // A triangle corner: an input vertex, or a node taken on `side`.
  struct Corner {
    int vertex = -1;
    int node = -1;
    int side = 0;
  };
  static Corner V(int v) { return {v, -1, 0}; }
  static Corner N(int n, int s) { return {-1, n, s}; }

  void addPiece(int source, const Corner& a, const Corner& b, const Corner& c) {
    pieces_.push_back({source, {a, b, c}});
  }

  // Quad q0 q1 q2 q3 (convex, counter-clockwise) as two triangles over the diagonal that gives the larger
  // smallest angle.
  void addQuad(int source, const Corner q[4]) {
    const auto pos = [&](const Corner& c) {
      return c.vertex >= 0 ? m_.vertices[std::size_t(c.vertex)] : nodes_[std::size_t(c.node)].x;
    };
    const double a02 = std::min(triangleMinAngleDeg(pos(q[0]), pos(q[1]), pos(q[2])),
                                triangleMinAngleDeg(pos(q[0]), pos(q[2]), pos(q[3])));
    const double a13 = std::min(triangleMinAngleDeg(pos(q[0]), pos(q[1]), pos(q[3])),
                                triangleMinAngleDeg(pos(q[1]), pos(q[2]), pos(q[3])));
    if (a02 >= a13) {
      addPiece(source, q[0], q[1], q[2]);
      addPiece(source, q[0], q[2], q[3]);
    } else {
      addPiece(source, q[0], q[1], q[3]);
      addPiece(source, q[1], q[2], q[3]);
    }
  }

  void link(int from, int to) {
    if (next_.count(from) || prev_.count(to)) throw CutInconsistent("the crossing curve branches");
    next_[from] = to;
    prev_[to] = from;
  }

  // First exit of the domain segment a -> b from the strip's outline, as a fraction of the segment (1 if none).
  double outlineExit(const Vec2d& a, const Vec2d& b) const {
    const int nb = int(dom_.boundary.size());
    double best = 1.0;
    for (int i = 0; i < nb; ++i) {
      const Vec2d& p = dom_.uv[std::size_t(dom_.boundary[std::size_t(i)])];
      const Vec2d& q = dom_.uv[std::size_t(dom_.boundary[std::size_t((i + 1) % nb)])];
      const double rx = b[0] - a[0], ry = b[1] - a[1], sx = q[0] - p[0], sy = q[1] - p[1];
      const double den = rx * sy - ry * sx;
      if (den == 0.0) continue;
      const double t = ((p[0] - a[0]) * sy - (p[1] - a[1]) * sx) / den;
      const double u = ((p[0] - a[0]) * ry - (p[1] - a[1]) * rx) / den;
      if (t > 0.0 && t <= 1.0 && u >= 0.0 && u <= 1.0) best = std::min(best, t);
    }
    return best;
  }

  // The cut-front point of a triangle the strip's outline passes through: on the segment from the real end of
  // the crossing curve (position x, domain uv) to the virtual crossing, where it leaves the strip (kept
  // snap_fraction away from the triangle's edges).
  int frontPoint(const Vec3d& x, const Vec2d& uv, const EdgeCrossing& virt) {
    const double tau = opt_.snap_fraction;
    const double lam = std::clamp(outlineExit(uv, virt.uv), tau, 1.0 - tau);
    return pierceNode(x + (virt.x - x) * lam);
  }

  // Per triangle: pieces and the directed contour segment, which runs with the + side on its left seen from
  // outside (direction n_sweep x n_mesh), so the region of the swept surface inside the organ lies on its left
  // in the domain.
  void splitTriangles() {
    touched_.assign(m_.triangles.size(), 0);
    for (std::size_t t = 0; t < m_.triangles.size(); ++t) {
      const auto& tri = m_.triangles[t];
      const int src = int(t);
      int zeros = 0;
      for (int v : tri) zeros += side_[std::size_t(v)] == 0;
      const auto edgeOf = [&](int k) { return tri_edge_[t * 3 + std::size_t(k)]; };  // corners k, k+1
      if (zeros == 3) throw CutInconsistent("a triangle lies in the cut");
      if (zeros == 2) {
        int k = 0;
        while (side_[std::size_t(tri[std::size_t(k)])] == 0) ++k;
        const int A = tri[std::size_t(k)], Z1 = tri[std::size_t((k + 1) % 3)], Z2 = tri[std::size_t((k + 2) % 3)];
        const int sA = side_[std::size_t(A)];
        touched_[t] = 1;
        const int n1 = vertexNode(Z1), n2 = vertexNode(Z2);
        addPiece(src, N(n1, sA), N(n2, sA), V(A));
        // The edge Z1 Z2 is on the crossing curve when the triangle across it lies on the other side; the +
        // triangle links it (A on the left of Z1 -> Z2).
        const int e = edgeOf((k + 1) % 3);
        const int other =
            edge_tris_[std::size_t(e)][0] == int(t) ? edge_tris_[std::size_t(e)][1] : edge_tris_[std::size_t(e)][0];
        int third = -1;
        for (int v : m_.triangles[std::size_t(other)])
          if (v != Z1 && v != Z2) third = v;
        if (sA > 0 && side_[std::size_t(third)] < 0) link(n1, n2);
        continue;
      }
      if (zeros == 1) {
        int k = 0;
        while (side_[std::size_t(tri[std::size_t(k)])] != 0) ++k;
        const int Z = tri[std::size_t(k)], A = tri[std::size_t((k + 1) % 3)], B = tri[std::size_t((k + 2) % 3)];
        const int sA = side_[std::size_t(A)], sB = side_[std::size_t(B)];
        touched_[t] = 1;
        const int z = vertexNode(Z);
        if (sA == sB) {
          addPiece(src, N(z, sA), V(A), V(B));
          continue;
        }
        const EdgeCrossing& xab = edge_x_[std::size_t(edgeOf((k + 1) % 3))];
        if (xab.real) {  // (Z, A, B) counter-clockwise: B lies left of Z -> x
          const int x = crossingNode(edgeOf((k + 1) % 3));
          addPiece(src, N(z, sA), V(A), N(x, sA));
          addPiece(src, N(z, sB), N(x, sB), V(B));
          if (sB > 0)
            link(z, x);
          else
            link(x, z);
        } else {
          const int p = frontPoint(m_.vertices[std::size_t(Z)], proj_[std::size_t(Z)].uv, xab);
          addPiece(src, N(z, sA), V(A), N(p, 0));
          addPiece(src, V(A), V(B), N(p, 0));
          addPiece(src, V(B), N(z, sB), N(p, 0));
          if (sB > 0)
            link(z, p);
          else
            link(p, z);
        }
        continue;
      }
      int ks[2], n = 0;
      for (int k = 0; k < 3; ++k)
        if (edge_x_[std::size_t(edgeOf(k))].cross) ks[n++] = k;
      if (n == 0) continue;
      if (n != 2) throw CutInconsistent("a triangle changes side on an odd number of edges");
      const int ea = edgeOf(ks[0]), eb = edgeOf(ks[1]);
      const bool ra = edge_x_[std::size_t(ea)].real, rb = edge_x_[std::size_t(eb)].real;
      if (!ra && !rb) continue;  // beyond the strip's edge: not cut
      touched_[t] = 1;
      // Lone vertex L: shared by the two side-changing edges (edges (0,1)->1, (1,2)->2, (2,0)->0).
      const int r = (ks[1] == ks[0] + 1) ? ks[1] : ks[0];
      const int L = tri[std::size_t(r)], A = tri[std::size_t((r + 1) % 3)], B = tri[std::size_t((r + 2) % 3)];
      const int eLA = edgeOf(r), eBL = edgeOf((r + 2) % 3);
      const int sL = side_[std::size_t(L)], sO = -sL;
      if (ra && rb) {
        const int xA = crossingNode(eLA), xB = crossingNode(eBL);
        addPiece(src, V(L), N(xA, sL), N(xB, sL));
        const Corner quad[4] = {N(xA, sO), V(A), V(B), N(xB, sO)};
        addQuad(src, quad);
        if (sL > 0)
          link(xA, xB);
        else
          link(xB, xA);
        continue;
      }
      // The strip's outline passes through this triangle: the crossing curve ends at a cut-front point inside.
      const bool real_on_LA = edge_x_[std::size_t(eLA)].real;
      const int er = real_on_LA ? eLA : eBL, ev = real_on_LA ? eBL : eLA;
      const int x = crossingNode(er);
      const int p = frontPoint(edge_x_[std::size_t(er)].x, edge_x_[std::size_t(er)].uv, edge_x_[std::size_t(ev)]);
      if (real_on_LA) {
        addPiece(src, V(L), N(x, sL), N(p, 0));
        addPiece(src, N(x, sO), V(A), N(p, 0));
        addPiece(src, V(A), V(B), N(p, 0));
        addPiece(src, V(B), V(L), N(p, 0));
        if (sL > 0)
          link(x, p);
        else
          link(p, x);
      } else {
        addPiece(src, V(L), V(A), N(p, 0));
        addPiece(src, V(A), V(B), N(p, 0));
        addPiece(src, V(B), N(x, sO), N(p, 0));
        addPiece(src, N(x, sL), V(L), N(p, 0));
        if (sL < 0)
          link(x, p);
        else
          link(p, x);
      }
    }
  }

  // The front: outline points strictly between arc positions s0 and s1 (counter-clockwise), the corners and
  // subdivisions so that no front edge is longer than the wall spacing; corners within 0.25 spacing of an end
  // are dropped (no tiny front edges).
  void appendArc(const Vec2d& from, double s0, const Vec2d& to, double s1, std::vector<int>& loop) {
    const double per = dom_.perimeter();
    double len = s1 - s0;
    while (len <= 0.0) len += per;
    std::vector<Vec2d> pts{from};
    const int nb = int(dom_.boundary.size());
    std::vector<std::pair<double, int>> corners;
    for (int i = 0; i < nb; ++i) {
      double d = dom_.boundary_s[std::size_t(i)] - s0;
      while (d <= 0.0) d += per;
      while (d > per) d -= per;
      if (d < len) corners.push_back({d, i});
    }
    std::sort(corners.begin(), corners.end());
    for (const auto& c : corners)
      if (c.first > 0.25 * h_ && len - c.first > 0.25 * h_)
        pts.push_back(dom_.uv[std::size_t(dom_.boundary[std::size_t(c.second)])]);
    pts.push_back(to);
    for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
      if (i > 0) addFront(pts[i], loop);
      const double l = std::hypot(pts[i + 1][0] - pts[i][0], pts[i + 1][1] - pts[i][1]);
      const int parts = std::max(1, int(std::ceil(l / h_ - 1e-9)));
      for (int j = 1; j < parts; ++j) {
        const double f = double(j) / parts;
        addFront({pts[i][0] + f * (pts[i + 1][0] - pts[i][0]), pts[i][1] + f * (pts[i + 1][1] - pts[i][1])}, loop);
      }
    }
  }

  void addFront(const Vec2d& uv, std::vector<int>& loop) {
    loop.push_back(int(nodes_.size()));
    nodes_.push_back({NodeKind::Front, liftFromDomain(s_, dom_, uv), uv});
    nodes_.back().s = outlinePosition(dom_, uv);
  }

  // Closed loops of the cut region's boundary: crossing chains between cut-front points joined by the arcs of
  // the strip's outline that lie inside the organ, closed crossing loops, and the whole outline when the strip
  // lies inside the organ with no front point (a cut through a tunnel of the organ).
  void buildLoops() {
    // Wall spacing: the mean length of the edges of the cut triangles (the surface's resolution along the cut).
    double len = 0.0;
    int count = 0;
    for (std::size_t t = 0; t < m_.triangles.size(); ++t)
      if (touched_[t])
        for (int k = 0; k < 3; ++k) {
          len += norm(m_.vertices[std::size_t(m_.triangles[t][k])] -
                      m_.vertices[std::size_t(m_.triangles[t][(k + 1) % 3])]);
          ++count;
        }
    h_ = opt_.wall_spacing_factor * len / std::max(1, count);
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      const bool has_next = next_.count(int(i)) > 0, has_prev = prev_.count(int(i)) > 0;
      const bool on_curve = nodes_[i].kind == NodeKind::Crossing || nodes_[i].kind == NodeKind::OnVertex;
      if (on_curve && !(has_next && has_prev))
        throw CutInconsistent("the crossing curve is open at a mesh edge or vertex");
      if (nodes_[i].kind == NodeKind::Pierce && has_next == has_prev)
        throw CutInconsistent("a cut-front point is not a chain end");
    }
    const double per = dom_.perimeter();
    // Next cut-front point counter-clockwise along the outline after the chain end `self`. Where the front
    // crosses a wall of an earlier cut, a chain end and a chain start coincide: at equal positions the start
    // comes first (the arc from the end goes on beyond it).
    const auto nextPierce = [&](int self) {
      int best = -1;
      double bd = std::numeric_limits<double>::infinity();
      bool best_end = true;
      for (int p : pierces_) {
        if (p == self) continue;
        double d = nodes_[std::size_t(p)].s - nodes_[std::size_t(self)].s;
        while (d <= 0.0) d += per;
        const bool end = next_.count(p) == 0;
        if (d < bd || (d == bd && best_end && !end)) bd = d, best = p, best_end = end;
      }
      return best;
    };
    std::vector<char> used(nodes_.size(), 0);
    for (int start : pierces_) {
      if (prev_.count(start) || used[std::size_t(start)]) continue;
      std::vector<int> loop;
      int cur = start;
      for (int guard = 0;; ++guard) {
        if (guard > int(pierces_.size())) throw CutInconsistent("cut-front arcs do not close");
        if (used[std::size_t(cur)]) throw CutInconsistent("a crossing chain is reached twice along the front");
        int v = cur;
        for (;;) {
          used[std::size_t(v)] = 1;
          loop.push_back(v);
          auto it = next_.find(v);
          if (it == next_.end()) break;
          v = it->second;
        }
        const int end = v, nxt = nextPierce(end);
        if (nxt < 0 || !next_.count(nxt) || prev_.count(nxt))
          throw CutInconsistent("along the outline a chain end is followed by another chain end");
        appendArc(nodes_[std::size_t(end)].uv, nodes_[std::size_t(end)].s, nodes_[std::size_t(nxt)].uv,
                  nodes_[std::size_t(nxt)].s, loop);
        if (nxt == start) break;
        cur = nxt;
      }
      used.resize(nodes_.size(), 1);
      loops_.push_back(std::move(loop));
    }
    used.resize(nodes_.size(), 1);
    for (std::size_t i = 0; i < used.size(); ++i) {
      if (used[i] || (nodes_[i].kind != NodeKind::Crossing && nodes_[i].kind != NodeKind::OnVertex)) continue;
      std::vector<int> loop;
      int v = int(i);
      while (!used[std::size_t(v)]) {
        used[std::size_t(v)] = 1;
        loop.push_back(v);
        v = next_.at(v);
      }
      if (v != int(i)) throw CutInconsistent("a crossing loop does not close on itself");
      loops_.push_back(std::move(loop));
    }
    if (pierces_.empty() && windingNumber(m_, s_.vertices[std::size_t(dom_.boundary[0])]) > 0.5) {
      std::vector<int> loop;
      const Vec2d p0 = dom_.uv[std::size_t(dom_.boundary[0])];
      addFront(p0, loop);
      appendArc(p0, 0.0, p0, per, loop);
      loops_.push_back(std::move(loop));
    }
  }

  // Shifts every loop node by a tiny step into the region (along the bisector of its interior angle) so that
  // coincident nodes of different loops (the crossings of the two coincident walls of an earlier cut) become
  // distinct points, then runs the constrained Delaunay triangulation.
  void triangulateWalls() {
    WallDomainInput in;
    in.uv.resize(nodes_.size());
    in.shared.resize(nodes_.size());
    const double delta = 1e-6 * h_;
    for (const auto& loop : loops_) {
      const std::size_t n = loop.size();
      if (n < 3) throw CutInconsistent("a cut loop has fewer than three points");
      for (std::size_t i = 0; i < n; ++i) {
        const Node &a = nodes_[std::size_t(loop[(i + n - 1) % n])], &b = nodes_[std::size_t(loop[i])],
                   &c = nodes_[std::size_t(loop[(i + 1) % n])];
        const double out = std::atan2(c.uv[1] - b.uv[1], c.uv[0] - b.uv[0]);
        const double back = std::atan2(a.uv[1] - b.uv[1], a.uv[0] - b.uv[0]);
        double sweep = std::fmod(back - out, 2.0 * kPi);
        if (sweep < 0.0) sweep += 2.0 * kPi;
        if (sweep <= 1e-12) sweep = 2.0 * kPi;  // a needle into the region (a slit of an earlier cut)
        const double dir = out + 0.5 * sweep;
        in.uv[std::size_t(loop[i])] = {b.uv[0] + delta * std::cos(dir), b.uv[1] + delta * std::sin(dir)};
      }
    }
    for (std::size_t i = 0; i < nodes_.size(); ++i)
      in.shared[i] = nodes_[i].kind == NodeKind::Pierce || nodes_[i].kind == NodeKind::Front;
    in.loops = loops_;
    in.spacing_m = h_;
    in.smoothing_iterations = opt_.smoothing_iterations;
    wall_ = triangulateCutWall(in);
  }

  SurfaceSplit assemble() {
    SurfaceSplit out;
    out.split = true;
    out.mesh.vertices = m_.vertices;
    out.vertex_side.assign(m_.vertices.size(), 0);
    out.binding_probe = m_.vertices;
    std::vector<char> seeded(m_.vertices.size(), 0);
    addNodeVertices(out, seeded);
    const std::vector<std::array<int, 2>> interior = addWallInteriorVertices(out);
    addSurfacePieces(out);
    addWalls(out, interior);
    out.wall_triangles = int(2 * wall_.triangles.size());
    out.contour_loops = int(loops_.size());
    out.chord_splits = wall_.chord_splits;
    out.wall_spacing_m = h_;
    labelInputVertices(out, seeded);
    // An input vertex lying on the swept surface looks from just off it, on its side (a segment from a point on
    // the surface would count as crossing it towards either side).
    for (std::size_t v = 0; v < m_.vertices.size(); ++v)
      if (!seeded[v] && std::fabs(proj_[v].offset) < probe_eps_)
        out.binding_probe[v] = m_.vertices[v] + proj_[v].normal * (2.0 * probe_eps_ * out.vertex_side[v]);
    checkSplitMesh(out);
    return out;
  }

  static int addVertex(SurfaceSplit& out, const Vec3d& x, int side, const Vec3d& probe) {
    out.mesh.vertices.push_back(x);
    out.vertex_side.push_back(std::int8_t(side));
    out.binding_probe.push_back(probe);
    return int(out.mesh.vertices.size()) - 1;
  }

  // The nodes' output vertices: a copy per side of a crossing (an input vertex on the cut is the + copy, `seeded`),
  // one of a pierce or front point.
  void addNodeVertices(SurfaceSplit& out, std::vector<char>& seeded) {
    for (auto& n : nodes_) {
      if (n.kind == NodeKind::Crossing || n.kind == NodeKind::OnVertex) {
        // Binding probes just off the strip on each side (a crossing may sit up to snap_fraction of an edge off it).
        const SweepProjection p = projectOntoSweep(s_, dom_, query_, n.x);
        if (n.kind == NodeKind::OnVertex) {
          n.v_plus = n.vertex;  // the input vertex is the + copy
          out.vertex_side[std::size_t(n.vertex)] = 1;
          out.binding_probe[std::size_t(n.vertex)] = p.closest + p.normal * probe_eps_;
          seeded[std::size_t(n.vertex)] = 1;
        } else {
          n.v_plus = addVertex(out, n.x, 1, p.closest + p.normal * probe_eps_);
        }
        n.v_minus = addVertex(out, n.x, -1, p.closest - p.normal * probe_eps_);
        ++out.crossings;
      } else {
        // Just ahead of the strip's outline (the front point may lie up to snap_fraction of an edge inside it),
        // in the strip's tangent plane: sees the material on both sides of the slit tip.
        Vec2d outward;
        const Vec2d q = outlinePoint(dom_, n.s, &outward);
        const Vec3d probe =
            liftFromDomain(s_, dom_, {q[0] + 10.0 * probe_eps_ * outward[0], q[1] + 10.0 * probe_eps_ * outward[1]});
        n.v_plus = n.v_minus = addVertex(out, n.x, 0, probe);
        ++(n.kind == NodeKind::Pierce ? out.pierce_points : out.front_points);
      }
    }
  }

  // The wall triangulation's interior points, one copy per side: {+, -} output vertices each.
  std::vector<std::array<int, 2>> addWallInteriorVertices(SurfaceSplit& out) const {
    std::vector<std::array<int, 2>> interior(wall_.interior_uv.size());
    for (std::size_t i = 0; i < interior.size(); ++i) {
      const Vec3d x = liftFromDomain(s_, dom_, wall_.interior_uv[i]);
      const SweepProjection p = projectOntoSweep(s_, dom_, query_, x);
      interior[i] = {addVertex(out, x, 1, x + p.normal * probe_eps_), addVertex(out, x, -1, x - p.normal * probe_eps_)};
    }
    return interior;
  }

  // Untouched triangles keep their order; each crossed triangle is replaced by its pieces.
  void addSurfacePieces(SurfaceSplit& out) const {
    TriangleMesh& mesh = out.mesh;
    const auto cornerVertex = [&](const Corner& c) {
      if (c.vertex >= 0) return c.vertex;
      const Node& n = nodes_[std::size_t(c.node)];
      return c.side < 0 ? n.v_minus : n.v_plus;
    };
    std::size_t piece = 0;
    out.min_split_angle_deg = 180.0;
    out.min_split_area_m2 = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < m_.triangles.size(); ++t) {
      if (!touched_[t]) {
        mesh.triangles.push_back(m_.triangles[t]);
        out.source_triangle.push_back(int(t));
        continue;
      }
      for (; piece < pieces_.size() && pieces_[piece].source == int(t); ++piece) {
        const auto& pc = pieces_[piece];
        const std::array<int, 3> tri{cornerVertex(pc.c[0]), cornerVertex(pc.c[1]), cornerVertex(pc.c[2])};
        mesh.triangles.push_back(tri);
        out.source_triangle.push_back(int(t));
        const Vec3d &a = mesh.vertices[std::size_t(tri[0])], &b = mesh.vertices[std::size_t(tri[1])],
                    &c = mesh.vertices[std::size_t(tri[2])];
        out.min_split_angle_deg = std::min(out.min_split_angle_deg, triangleMinAngleDeg(a, b, c));
        out.min_split_area_m2 = std::min(out.min_split_area_m2, triangleArea(a, b, c));
      }
    }
  }

  // The cut walls, one per side, from the wall triangulation (flagged in out.wall).
  void addWalls(SurfaceSplit& out, const std::vector<std::array<int, 2>>& interior) const {
    TriangleMesh& mesh = out.mesh;
    const int nn = int(nodes_.size());
    out.wall.assign(mesh.triangles.size(), 0);
    const auto wallVertex = [&](int id, int side) {
      if (id >= nn) return interior[std::size_t(id - nn)][side > 0 ? 0 : 1];
      return side > 0 ? nodes_[std::size_t(id)].v_plus : nodes_[std::size_t(id)].v_minus;
    };
    out.min_wall_angle_deg = 180.0;
    out.min_wall_area_m2 = std::numeric_limits<double>::infinity();
    for (const auto& f : wall_.triangles) {
      // The - side's wall faces +normal (counter-clockwise in the domain), the + side's wall faces -normal.
      const std::array<int, 3> minus{wallVertex(f[0], -1), wallVertex(f[1], -1), wallVertex(f[2], -1)};
      const std::array<int, 3> plus{wallVertex(f[0], 1), wallVertex(f[2], 1), wallVertex(f[1], 1)};
      for (const auto& tri : {minus, plus}) {
        mesh.triangles.push_back(tri);
        out.source_triangle.push_back(-1);
        out.wall.push_back(1);
      }
      const Vec3d &a = mesh.vertices[std::size_t(minus[0])], &b = mesh.vertices[std::size_t(minus[1])],
                  &c = mesh.vertices[std::size_t(minus[2])];
      out.min_wall_angle_deg = std::min(out.min_wall_angle_deg, triangleMinAngleDeg(a, b, c));
      out.min_wall_area_m2 = std::min(out.min_wall_area_m2, triangleArea(a, b, c));
    }
  }

  // The split surface must be closed, oriented, without degenerate triangles and manifold at every vertex.
  static void checkSplitMesh(SurfaceSplit& out) {
    const MeshReport rep = analyzeMesh(out.mesh);
    if (!rep.closed() || rep.inconsistent_edges != 0 || rep.degenerate_triangles != 0)
      throw CutInconsistent(
          "the split surface is not closed and oriented (boundary " + std::to_string(rep.boundary_edges) +
          ", non-manifold " + std::to_string(rep.non_manifold_edges) + ", inconsistent " +
          std::to_string(rep.inconsistent_edges) + ", degenerate " + std::to_string(rep.degenerate_triangles) + ")");
    const int bad_vertices = nonManifoldVertexCount(out.mesh);
    if (bad_vertices != 0)
      throw CutInconsistent(std::to_string(bad_vertices) + " non-manifold vertices after the split");
    out.components = rep.components;
  }

  // Input vertices take the side of the nearest new vertex over the split mesh's edges (never through the cut
  // front); vertices of components the cut does not reach keep the side of their offset.
  void labelInputVertices(SurfaceSplit& out, const std::vector<char>& seeded) const {
    const auto& mesh = out.mesh;
    const std::size_t nv = mesh.vertices.size(), n_in = m_.vertices.size();
    std::vector<std::vector<int>> adj(nv);
    for (const auto& t : mesh.triangles)
      for (int k = 0; k < 3; ++k)
        adj[std::size_t(t[k])].push_back(t[(k + 1) % 3]), adj[std::size_t(t[(k + 1) % 3])].push_back(t[k]);
    std::vector<int> queue;
    std::vector<char> seen(nv, 0);
    for (std::size_t v = 0; v < nv; ++v)
      if ((v >= n_in || seeded[v]) && out.vertex_side[v] != 0) queue.push_back(int(v)), seen[v] = 1;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const int v = queue[head];
      for (int w : adj[std::size_t(v)])
        if (!seen[std::size_t(w)] && std::size_t(w) < n_in) {
          seen[std::size_t(w)] = 1;
          out.vertex_side[std::size_t(w)] = out.vertex_side[std::size_t(v)];
          queue.push_back(w);
        }
    }
    for (std::size_t v = 0; v < n_in; ++v)
      if (!seen[v])
        out.vertex_side[v] = std::int8_t(
            !far_[v] ? side_[v] : (projectOntoSweep(s_, dom_, query_, m_.vertices[v]).offset >= 0.0 ? 1 : -1));
  }

  struct Piece {
    int source;
    Corner c[3];
  };

  const TriangleMesh& m_;
  const SweptSurface& s_;
  const SurfaceSplitOptions& opt_;
  SweepDomain dom_;
  SweptSurfaceQuery query_;  // the closest-triangle search of every projection (same answers, far runs skipped)
  double size_ = 0.0, probe_eps_ = 0.0, h_ = 0.0;
  std::vector<std::array<int, 2>> edges_;
  std::vector<int> tri_edge_;
  std::vector<std::array<int, 2>> edge_tris_;
  std::vector<int> side_;              // +1 / -1, 0 = snapped onto the cut
  std::vector<SweepProjection> proj_;  // per input vertex (not for far ones)
  std::vector<char> far_;              // farther than two edges from the strip's bounding box
  std::vector<std::vector<int>> adj_;
  std::vector<int> vertex_node_;  // node of a snapped vertex, -1
  std::vector<EdgeCrossing> edge_x_;
  std::vector<Node> nodes_;
  std::vector<int> pierces_;
  std::vector<Piece> pieces_;
  std::vector<char> touched_;
  std::map<int, int> next_, prev_;
  std::vector<std::vector<int>> loops_;
  WallTriangulation wall_;
};

}  // namespace

SurfaceSplit splitSurfaceBySweep(const TriangleMesh& mesh, const SweptSurface& sweep, const SurfaceSplitOptions& opt) {
  if (!opt.input_checked) checkInputMesh(mesh);
  if (!(opt.snap_fraction > 0.0 && opt.snap_fraction < 0.5))
    throw InputError("cut", "snap_fraction", "must be in (0, 0.5)");
  if (!(opt.wall_spacing_factor > 0.0)) throw InputError("cut", "wall_spacing_factor", "must be > 0");
  unfoldSweptSurface(sweep);  // validates the strip (InputError) before any attempt
  Vec3d lo = mesh.vertices.front(), hi = lo;
  for (const auto& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
  const double size = norm(hi - lo);
  // Perturbations for the retries: fixed unit directions (deterministic) and growing sizes relative to the mesh:
  // rounding-level first, then up to 1e-3 of the organ (a crossing curve that grazes the cut front, e.g. along a
  // wall of an earlier cut nearly parallel to the blade, needs the front moved by more than rounding).
  const Vec3d dirs[4] = {Vec3d(0, 0, 0), Vec3d(0.48, 0.36, 0.8), Vec3d(-0.6, 0.64, 0.48), Vec3d(0.36, -0.48, 0.8)};
  const double sizes[4] = {0.0, 2e-6, 1e-4, 1e-3};
  std::string reason;
  for (int attempt = 0; attempt < std::max(1, opt.max_attempts); ++attempt) {
    SweptSurface s = sweep;
    const Vec3d shift = dirs[attempt % 4] * (sizes[attempt % 4] * size * double(1 + attempt / 4));
    for (auto& v : s.vertices) v += shift;
    try {
      SurfaceSplit r = Splitter(mesh, s, opt).run();
      r.attempts = attempt + 1;
      return r;
    } catch (const CutInconsistent& e) {
      reason = e.what();
    }
  }
  throw CutSplitFailed("the split stayed inconsistent after " + std::to_string(opt.max_attempts) +
                       " perturbed attempts: " + reason);
}

}  // namespace inc
