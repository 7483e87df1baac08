// Cut-wall triangulation: lattice down-sampling of the cut region and CGAL constrained Delaunay with the contour.
#include "host/cut/cut_wall_cdt.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <set>
#include <utility>

#include "model/input_error.h"

#if INCISION_HAVE_CGAL
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_no_edge_refinement_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#endif

namespace inc {

#if INCISION_HAVE_CGAL

namespace {

struct NodeId {
  int id = -1;  // points the Delaunay refinement adds keep -1
};
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<NodeId, K, CGAL::Delaunay_mesh_vertex_base_2<K>>;
using Fbi = CGAL::Triangulation_face_base_with_info_2<int, K>;  // -1 unknown, 0 outside, 1 inside
using Fb = CGAL::Delaunay_mesh_face_base_2<K, CGAL::Constrained_triangulation_face_base_2<K, Fbi>>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;
using Criteria = CGAL::Delaunay_mesh_size_criteria_2<Cdt>;
using Point = K::Point_2;

struct Segment {
  Vec2d a, b;
};

double distanceToSegment(const Vec2d& p, const Segment& s) {
  const double ex = s.b[0] - s.a[0], ey = s.b[1] - s.a[1], l2 = ex * ex + ey * ey;
  const double t = l2 > 0.0 ? std::clamp(((p[0] - s.a[0]) * ex + (p[1] - s.a[1]) * ey) / l2, 0.0, 1.0) : 0.0;
  return std::hypot(s.a[0] + t * ex - p[0], s.a[1] + t * ey - p[1]);
}

class WallCdt {
 public:
  WallCdt(const WallDomainInput& in) : in_(in) {
    for (const auto& loop : in.loops)
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const int a = loop[i], b = loop[(i + 1) % loop.size()];
        if (a == b) throw CutInconsistent("a cut loop repeats a node");
        if (!directed_.insert({a, b}).second) throw CutInconsistent("a cut loop edge is traversed twice");
        segments_.push_back({in.uv[std::size_t(a)], in.uv[std::size_t(b)]});
      }
  }

  // Triangulates nodes + interior points with the loop constraints and marks the faces of the region.
  void build(const std::vector<Vec2d>& interior) {
    cdt_.clear();
    const int nn = int(in_.uv.size());
    std::vector<std::pair<Point, NodeId>> pts;
    pts.reserve(in_.uv.size() + interior.size());
    for (int i = 0; i < nn; ++i)
      pts.push_back({Point(in_.uv[std::size_t(i)][0], in_.uv[std::size_t(i)][1]), NodeId{i}});
    for (std::size_t i = 0; i < interior.size(); ++i)
      pts.push_back({Point(interior[i][0], interior[i][1]), NodeId{nn + int(i)}});
    cdt_.insert(pts.begin(), pts.end());
    if (cdt_.number_of_vertices() != pts.size()) throw CutInconsistent("two cut-wall points coincide");
    handles_.assign(pts.size(), Cdt::Vertex_handle());
    for (auto v = cdt_.finite_vertices_begin(); v != cdt_.finite_vertices_end(); ++v)
      handles_[std::size_t(v->info().id)] = v;
    for (const auto& e : directed_)
      cdt_.insert_constraint(handles_[std::size_t(e.first)], handles_[std::size_t(e.second)]);
    if (cdt_.number_of_vertices() != pts.size()) throw CutInconsistent("cut loops intersect each other");
    for (const auto& e : directed_) {
      Cdt::Face_handle f;
      int i;
      if (!cdt_.is_edge(handles_[std::size_t(e.first)], handles_[std::size_t(e.second)], f, i))
        throw CutInconsistent("a cut loop edge passes through another point");
    }
    markDomain();
  }

  bool inside(const Cdt::Face_handle& f) const { return !cdt_.is_infinite(f) && f->info() == 1; }

  // Lattice points inside the region at least 0.5 spacing from every loop edge.
  std::vector<Vec2d> latticeSamples() const {
    const double h = in_.spacing_m;
    Vec2d lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    Vec2d hi{-lo[0], -lo[1]};
    for (const auto& s : segments_)
      for (const Vec2d* p : {&s.a, &s.b})
        for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], (*p)[a]), hi[a] = std::max(hi[a], (*p)[a]);
    std::vector<Vec2d> out;
    const double row = h * std::sqrt(3.0) / 2.0;
    const long rows = long(std::ceil((hi[1] - lo[1]) / row)), cols = long(std::ceil((hi[0] - lo[0]) / h)) + 1;
    if (double(rows) * double(cols) > 4e6) throw CutInconsistent("cut-wall spacing far below the cut's size");
    Cdt::Face_handle hint;
    for (long j = 0; j <= rows; ++j)
      for (long i = 0; i <= cols; ++i) {
        const Vec2d p{lo[0] + (double(i) + (j % 2 ? 0.5 : 0.0)) * h, lo[1] + double(j) * row};
        hint = cdt_.locate(Point(p[0], p[1]), hint);
        if (!inside(hint) || nearBoundary(p, 0.5 * h)) continue;
        out.push_back(p);
      }
    return out;
  }

  // One Jacobi step of area-weighted centroid smoothing of the interior points (ids >= node count).
  std::vector<Vec2d> smoothed(const std::vector<Vec2d>& interior) const {
    std::vector<Vec2d> out = interior;
    const int nn = int(in_.uv.size());
    for (std::size_t i = 0; i < interior.size(); ++i) {
      const auto v = handles_[std::size_t(nn) + i];
      double wx = 0.0, wy = 0.0, w = 0.0;
      bool ok = true;
      auto f = cdt_.incident_faces(v), done = f;
      do {
        if (!inside(f)) {
          ok = false;
          break;
        }
        const Point &a = f->vertex(0)->point(), &b = f->vertex(1)->point(), &c = f->vertex(2)->point();
        const double area = 0.5 * ((b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x()));
        wx += area * (a.x() + b.x() + c.x()) / 3.0;
        wy += area * (a.y() + b.y() + c.y()) / 3.0;
        w += area;
      } while (++f != done);
      if (!ok || !(w > 0.0)) continue;
      const Vec2d p{wx / w, wy / w};
      const auto located = cdt_.locate(Point(p[0], p[1]));
      if (inside(located) && !nearBoundary(p, 0.3 * in_.spacing_m)) out[i] = p;
    }
    return out;
  }

  // Delaunay refinement that never splits a loop edge (the loop edges are shared with the split mesh): the
  // circumcentre of a triangle with an angle under ~20.7 deg (CGAL bound B = 0.125) or an edge longer than 1.5
  // spacings is added unless it lies outside the region or encroaches a loop edge. Returns all interior points.
  std::vector<Vec2d> refined() {
    for (auto f = cdt_.all_faces_begin(); f != cdt_.all_faces_end(); ++f) f->set_in_domain(inside(f));
    CGAL::Delaunay_mesher_no_edge_refinement_2<Cdt, Criteria> mesher(cdt_, Criteria(0.125, 1.5 * in_.spacing_m));
    mesher.init(true);
    mesher.refine_mesh();
    std::vector<Vec2d> out;
    const int nn = int(in_.uv.size());
    for (auto v = cdt_.finite_vertices_begin(); v != cdt_.finite_vertices_end(); ++v)
      if (v->info().id < 0 || v->info().id >= nn) out.push_back({v->point().x(), v->point().y()});
    std::sort(out.begin(), out.end());  // deterministic order for the caller's vertex numbering
    return out;
  }

  // Midpoints of inner edges joining two shared nodes (empty when there are none).
  std::vector<Vec2d> sharedChordMidpoints() const {
    std::set<std::pair<int, int>> chords;
    const int nn = int(in_.uv.size());
    for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f) {
      if (f->info() != 1) continue;
      for (int i = 0; i < 3; ++i) {
        if (f->is_constrained(i)) continue;
        const int a = f->vertex(Cdt::ccw(i))->info().id, b = f->vertex(Cdt::cw(i))->info().id;
        if (a < nn && b < nn && in_.shared[std::size_t(a)] && in_.shared[std::size_t(b)])
          chords.insert({std::min(a, b), std::max(a, b)});
      }
    }
    std::vector<Vec2d> mids;
    for (const auto& c : chords) {
      const Vec2d &p = in_.uv[std::size_t(c.first)], &q = in_.uv[std::size_t(c.second)];
      mids.push_back({0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])});
    }
    return mids;
  }

  std::vector<std::array<int, 3>> triangles() const {
    std::vector<std::array<int, 3>> out;
    for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f)
      if (f->info() == 1) out.push_back({f->vertex(0)->info().id, f->vertex(1)->info().id, f->vertex(2)->info().id});
    return out;
  }

 private:
  bool nearBoundary(const Vec2d& p, double r) const {
    for (const auto& s : segments_)
      if (distanceToSegment(p, s) < r) return true;
    return false;
  }

  // A face is inside when it lies left of a loop edge it touches; marks spread across unconstrained edges.
  // Conflicting marks mean the loops do not bound a consistent region.
  void markDomain() {
    for (auto f = cdt_.all_faces_begin(); f != cdt_.all_faces_end(); ++f) f->info() = cdt_.is_infinite(f) ? 0 : -1;
    std::deque<Cdt::Face_handle> queue;
    for (auto f = cdt_.all_faces_begin(); f != cdt_.all_faces_end(); ++f) {
      if (cdt_.is_infinite(f)) {
        queue.push_back(f);
        continue;
      }
      for (int i = 0; i < 3; ++i) {
        if (!f->is_constrained(i)) continue;
        const int a = f->vertex(Cdt::ccw(i))->info().id, b = f->vertex(Cdt::cw(i))->info().id;
        const int mark = directed_.count({a, b}) ? 1 : 0;
        if (f->info() >= 0 && f->info() != mark) throw CutInconsistent("a cut-wall face is both inside and outside");
        f->info() = mark;
      }
      if (f->info() >= 0) queue.push_back(f);
    }
    while (!queue.empty()) {
      const Cdt::Face_handle f = queue.front();
      queue.pop_front();
      for (int i = 0; i < 3; ++i) {
        if (f->is_constrained(i)) continue;
        const Cdt::Face_handle g = f->neighbor(i);
        if (g->info() < 0) {
          g->info() = f->info();
          queue.push_back(g);
        } else if (g->info() != f->info() && !cdt_.is_infinite(g) && !cdt_.is_infinite(f)) {
          throw CutInconsistent("the cut loops do not enclose a consistent region");
        }
      }
    }
    for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f)
      if (f->info() < 0) f->info() = 0;
  }

  const WallDomainInput& in_;
  std::set<std::pair<int, int>> directed_;
  std::vector<Segment> segments_;
  Cdt cdt_;
  std::vector<Cdt::Vertex_handle> handles_;
};

}  // namespace

WallTriangulation triangulateCutWall(const WallDomainInput& in) {
  if (!(in.spacing_m > 0.0) || !std::isfinite(in.spacing_m)) throw CutInconsistent("cut-wall spacing must be positive");
  if (in.shared.size() != in.uv.size()) throw CutInconsistent("one shared flag per node needed");
  WallCdt cdt(in);
  WallTriangulation out;
  cdt.build({});
  std::vector<Vec2d> interior = cdt.latticeSamples();
  for (int it = 0; it < in.smoothing_iterations && !interior.empty(); ++it) {
    cdt.build(interior);
    interior = cdt.smoothed(interior);
  }
  cdt.build(interior);
  interior = cdt.refined();
  cdt.build(interior);
  for (int round = 0; round < 8; ++round) {
    const std::vector<Vec2d> mids = cdt.sharedChordMidpoints();
    if (mids.empty()) break;
    out.chord_splits += int(mids.size());
    interior.insert(interior.end(), mids.begin(), mids.end());
    cdt.build(interior);
  }
  if (!cdt.sharedChordMidpoints().empty()) throw CutInconsistent("inner cut-wall edges still join front points");
  out.interior_uv = std::move(interior);
  out.triangles = cdt.triangles();
  return out;
}

#else

WallTriangulation triangulateCutWall(const WallDomainInput&) {
  throw InputError("cut", "build", "cut walls need CGAL (libcgal-dev); this build was configured without it");
}

#endif

}  // namespace inc
