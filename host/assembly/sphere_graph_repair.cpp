// connectSphereGraph: mesh pieces, sphere groups per piece, links across narrow gaps inside the mesh, drops.
#include "host/assembly/sphere_graph_repair.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numeric>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "host/assembly/metaball_pack_cover.h"
#include "host/assembly/point_grid.h"
#include "host/io/triangle_bvh.h"

namespace inc {
namespace {

constexpr int kLinksPerStraggler = 3;  // three links hold a sphere in place; one would only hinge it

// Connected pieces of the surface (triangles sharing a vertex), each as its own mesh.
std::vector<TriangleMesh> meshPieces(const TriangleMesh& surface) {
  pack::UnionFind uf(int(surface.vertices.size()));
  for (const auto& t : surface.triangles) {
    uf.join(t[0], t[1]);
    uf.join(t[1], t[2]);
  }
  std::unordered_map<int, std::size_t> piece_of_root;
  std::vector<TriangleMesh> pieces;
  std::vector<std::unordered_map<int, int>> local(0);
  for (const auto& t : surface.triangles) {
    const int root = uf.find(t[0]);
    auto [it, fresh] = piece_of_root.emplace(root, pieces.size());
    if (fresh) {
      pieces.emplace_back();
      local.emplace_back();
    }
    TriangleMesh& piece = pieces[it->second];
    std::unordered_map<int, int>& index = local[it->second];
    std::array<int, 3> tri{};
    for (int c = 0; c < 3; ++c) {
      auto [v, added] = index.emplace(t[std::size_t(c)], int(piece.vertices.size()));
      if (added) piece.vertices.push_back(surface.vertices[std::size_t(t[std::size_t(c)])]);
      tri[std::size_t(c)] = v->second;
    }
    piece.triangles.push_back(tri);
  }
  return pieces;
}

// Which piece encloses p: the smallest piece whose surface holds it (a piece inside another's cavity wins), else
// the nearest one.
int enclosingPiece(const Vec3d& p, const std::vector<std::unique_ptr<pack::SurfaceDistance>>& inside,
                   const std::vector<double>& volume) {
  int best = -1;
  for (std::size_t k = 0; k < inside.size(); ++k)
    if (inside[k]->insideByRays(p) && (best < 0 || volume[k] < volume[std::size_t(best)])) best = int(k);
  if (best >= 0) return best;
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < inside.size(); ++k) {
    const double d = inside[k]->bvh().nearest(p).distance2;
    if (d < nearest) {
      nearest = d;
      best = int(k);
    }
  }
  return best;
}

double enclosedVolume(const TriangleMesh& m) {
  double v = 0.0;
  for (const auto& t : m.triangles)
    v += dot(m.vertices[std::size_t(t[0])], cross(m.vertices[std::size_t(t[1])], m.vertices[std::size_t(t[2])]));
  return std::fabs(v) / 6.0;
}

// The sphere graph during the repair: groups (union-find over links), the mesh piece and anchor group of each.
struct Groups {
  pack::UnionFind uf;
  std::vector<int> piece;   // per sphere
  std::vector<int> anchor;  // per piece: a sphere of its largest group as filled (-1: the piece holds none)
  explicit Groups(int n) : uf(n), piece(std::size_t(n), 0) {}
  bool anchored(int i) {
    return anchor[std::size_t(piece[std::size_t(i)])] >= 0 &&
           uf.find(i) == uf.find(anchor[std::size_t(piece[std::size_t(i)])]);
  }
};

// Groups, pieces and anchors of the model as filled.
Groups groupSpheres(const MetaballModel& mb, const std::vector<TriangleMesh>& pieces) {
  const int n = int(mb.size());
  Groups g(n);
  for (const auto& l : mb.links) g.uf.join(l[0], l[1]);
  std::vector<int> members(std::size_t(n), 0);
  for (int i = 0; i < n; ++i) ++members[std::size_t(g.uf.find(i))];
  if (pieces.size() > 1) {
    std::vector<std::unique_ptr<pack::SurfaceDistance>> inside;
    std::vector<double> volume;
    for (const TriangleMesh& p : pieces) {
      inside.push_back(std::make_unique<pack::SurfaceDistance>(p));
      volume.push_back(enclosedVolume(p));
    }
    std::unordered_map<int, int> piece_of_group;  // by the group's first sphere
    for (int i = 0; i < n; ++i) {
      const int root = g.uf.find(i);
      auto it = piece_of_group.find(root);
      if (it == piece_of_group.end())
        it = piece_of_group.emplace(root, enclosingPiece(mb.rest_centers[std::size_t(i)], inside, volume)).first;
      g.piece[std::size_t(i)] = it->second;
    }
  }
  g.anchor.assign(std::max<std::size_t>(1, pieces.size()), -1);
  for (int i = 0; i < n; ++i) {
    int& a = g.anchor[std::size_t(g.piece[std::size_t(i)])];
    if (a < 0 || members[std::size_t(g.uf.find(i))] > members[std::size_t(g.uf.find(a))]) a = i;
  }
  return g;
}

// True when the segment a-b lies inside the surface (sampled at steps of at most `step`, ends excluded); with no
// surface the body is convex and holds every segment between two of its points.
bool segmentInside(const Vec3d& a, const Vec3d& b, double step, const pack::SurfaceDistance* surface) {
  if (!surface) return true;
  const int n = std::max(3, int(std::ceil(norm(b - a) / step)));
  for (int s = 1; s < n; ++s)
    if (!surface->insideByRays(a + (b - a) * (double(s) / n))) return false;
  return true;
}

struct NewLink {
  int i, j;
};

// Links from the spheres of one group to their nearest spheres of other groups of the same piece.
std::vector<NewLink> linksOutOf(const std::vector<int>& group, const MetaballModel& mb, Groups& g,
                                const PointGrid& centres, double reach, const pack::SurfaceDistance* surface,
                                double max_gap) {
  std::vector<NewLink> out;
  const int root = g.uf.find(group.front());
  std::vector<std::pair<double, int>> near;
  for (int i : group) {
    const Vec3d& ci = mb.rest_centers[std::size_t(i)];
    const double ri = mb.rest_radii[std::size_t(i)];
    near.clear();
    centres.forEachWithin(ci, reach, [&](std::int32_t j) {
      if (g.piece[std::size_t(j)] != g.piece[std::size_t(i)] || g.uf.find(j) == root) return true;
      const double gap = norm(ci - mb.rest_centers[std::size_t(j)]) - ri - mb.rest_radii[std::size_t(j)];
      if (gap <= max_gap) near.emplace_back(gap, j);
      return true;
    });
    std::sort(near.begin(), near.end());
    int taken = 0;
    for (const auto& [gap, j] : near) {
      if (taken == kLinksPerStraggler) break;
      const double step = 0.5 * std::min(ri, mb.rest_radii[std::size_t(j)]);
      if (!segmentInside(ci, mb.rest_centers[std::size_t(j)], step, surface)) continue;
      out.push_back({std::min(i, j), std::max(i, j)});
      ++taken;
    }
  }
  return out;
}

// Passes over the unanchored groups, smallest first, linking each to what lies near it, until a pass links none.
int linkStragglers(MetaballModel& mb, Groups& g, const pack::SurfaceDistance* surface, double max_gap) {
  const int n = int(mb.size());
  double r_max = 0.0;
  for (double r : mb.rest_radii) r_max = std::max(r_max, r);
  // Every sphere a link may reach lies within 2 r_max + max_gap of the centre (gap = distance - r_i - r_j).
  const double reach = 2.0 * r_max + max_gap;
  Vec3d lo = mb.rest_centers.empty() ? Vec3d() : mb.rest_centers.front(), hi = lo;
  for (const Vec3d& c : mb.rest_centers)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[a]);
      hi[a] = std::max(hi[a], c[a]);
    }
  PointGrid centres(mb.rest_centers, lo, hi, reach, mb.rest_centers.size() * 4 + 1);
  for (int i = 0; i < n; ++i) centres.insert(i);
  int added = 0;
  for (bool progress = true; progress;) {
    progress = false;
    std::unordered_map<int, std::vector<int>> groups;
    for (int i = 0; i < n; ++i)
      if (!g.anchored(i)) groups[g.uf.find(i)].push_back(i);
    std::vector<std::vector<int>> order;
    for (auto& [root, members] : groups) order.push_back(std::move(members));
    std::sort(order.begin(), order.end(), [](const std::vector<int>& a, const std::vector<int>& b) {
      return a.size() != b.size() ? a.size() < b.size() : a.front() < b.front();
    });
    for (const std::vector<int>& group : order) {
      if (g.anchored(group.front())) continue;  // joined through a group linked earlier in this pass
      const std::vector<NewLink> links = linksOutOf(group, mb, g, centres, reach, surface, max_gap);
      for (const NewLink& l : links) {
        mb.links.push_back({std::int32_t(l.i), std::int32_t(l.j)});
        mb.link_rest_lengths.push_back(norm(mb.rest_centers[std::size_t(l.i)] - mb.rest_centers[std::size_t(l.j)]));
        g.uf.join(l.i, l.j);
      }
      added += int(links.size());
      progress = progress || !links.empty();
    }
  }
  return added;
}

// Removes the spheres still outside their piece's anchored group; their mass goes to the nearest kept sphere of the
// same piece. Returns the mass moved.
double dropUnanchored(MetaballModel& mb, Groups& g, int& dropped) {
  const int n = int(mb.size());
  std::vector<int> new_index(std::size_t(n), -1);
  int kept = 0;
  for (int i = 0; i < n; ++i)
    if (g.anchored(i)) new_index[std::size_t(i)] = kept++;
  dropped = n - kept;
  if (dropped == 0) return 0.0;
  double moved = 0.0;
  const bool weighed = mb.masses.size() == mb.size();
  for (int i = 0; weighed && i < n; ++i) {
    if (new_index[std::size_t(i)] >= 0) continue;
    int nearest = -1;
    double best = std::numeric_limits<double>::infinity();
    for (int j = 0; j < n; ++j) {
      if (new_index[std::size_t(j)] < 0 || g.piece[std::size_t(j)] != g.piece[std::size_t(i)]) continue;
      const double d = norm2(mb.rest_centers[std::size_t(i)] - mb.rest_centers[std::size_t(j)]);
      if (d < best) {
        best = d;
        nearest = j;
      }
    }
    mb.masses[std::size_t(nearest)] += mb.masses[std::size_t(i)];
    moved += mb.masses[std::size_t(i)];
  }
  MetaballModel out;
  for (int i = 0; i < n; ++i) {
    if (new_index[std::size_t(i)] < 0) continue;
    out.rest_centers.push_back(mb.rest_centers[std::size_t(i)]);
    out.rest_radii.push_back(mb.rest_radii[std::size_t(i)]);
    if (weighed) out.masses.push_back(mb.masses[std::size_t(i)]);
  }
  for (std::size_t l = 0; l < mb.links.size(); ++l) {
    const int a = new_index[std::size_t(mb.links[l][0])], b = new_index[std::size_t(mb.links[l][1])];
    if (a < 0 || b < 0) continue;
    out.links.push_back({std::int32_t(a), std::int32_t(b)});
    out.link_rest_lengths.push_back(mb.link_rest_lengths[l]);
  }
  mb = std::move(out);
  return moved;
}

// Links sorted by (i, j) with their rest lengths, as the overlap linking leaves them.
void sortLinks(MetaballModel& mb) {
  std::vector<std::size_t> order(mb.links.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return mb.links[a] < mb.links[b]; });
  std::vector<std::array<std::int32_t, 2>> links(order.size());
  std::vector<double> rest(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    links[k] = mb.links[order[k]];
    rest[k] = mb.link_rest_lengths[order[k]];
  }
  mb.links = std::move(links);
  mb.link_rest_lengths = std::move(rest);
}

}  // namespace

SphereGraphRepair connectSphereGraph(MetaballModel& mb, const TriangleMesh& surface, double max_gap) {
  SphereGraphRepair rep;
  const std::vector<TriangleMesh> pieces = meshPieces(surface);
  rep.mesh_pieces = std::max(1, int(pieces.size()));
  rep.components_before = rep.components_after = sphereGraphComponents(mb);
  if (mb.size() == 0 || rep.components_before <= 1) return rep;

  Groups g = groupSpheres(mb, pieces);
  for (int i = 0; i < int(mb.size()); ++i) rep.stragglers += g.anchored(i) ? 0 : 1;
  if (rep.stragglers == 0) return rep;  // one group per piece already
  const std::unique_ptr<const pack::SurfaceDistance> whole =
      surface.triangles.empty() ? nullptr : std::make_unique<const pack::SurfaceDistance>(surface);
  rep.links_added = linkStragglers(mb, g, whole.get(), max_gap);
  rep.dropped_mass = dropUnanchored(mb, g, rep.dropped);
  rep.linked = rep.stragglers - rep.dropped;
  sortLinks(mb);
  rep.components_after = sphereGraphComponents(mb);
  return rep;
}

std::string describeSphereGraphRepair(const SphereGraphRepair& r, std::size_t spheres) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%zu spheres, %d straggler%s linked (%d link%s), %d dropped", spheres, r.linked,
                r.linked == 1 ? "" : "s", r.links_added, r.links_added == 1 ? "" : "s", r.dropped);
  std::string s = buf;
  if (r.dropped_mass > 0) {
    std::snprintf(buf, sizeof buf, " (%.3g g moved to neighbours)", 1e3 * r.dropped_mass);
    s += buf;
  }
  std::snprintf(buf, sizeof buf, ", %d component%s for %d mesh piece%s", r.components_after,
                r.components_after == 1 ? "" : "s", r.mesh_pieces, r.mesh_pieces == 1 ? "" : "s");
  return s + buf;
}

}  // namespace inc
