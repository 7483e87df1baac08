// Cut-surface state across successive cuts and the visibility-filtered skin binding of the split surface.
#include "host/cut/cut_surface_state.h"

#include <algorithm>
#include <array>

namespace inc {

CutSurfaceState cutSurfaceState(const TriangleMesh& rest) {
  CutSurfaceState s;
  s.mesh = rest;
  s.wall.assign(rest.triangles.size(), 0);
  s.probe = rest.vertices;
  return s;
}

SurfaceSplit applySurfaceCut(CutSurfaceState& state, const SweptSurface& sweep, const SurfaceSplitOptions& options) {
  SurfaceSplit r;
  SurfaceSplitOptions opt = options;
  opt.input_checked = opt.input_checked || state.checked;
  try {
    r = splitSurfaceBySweep(state.mesh, sweep, opt);
  } catch (const CutSplitFailed& e) {
    r.failure = e.reason();  // the surface stays as it is for this cut; spheres and links are still cut
    return r;
  }
  if (!r.split) return r;
  std::vector<std::uint8_t> wall(r.mesh.triangles.size(), 1);
  for (std::size_t t = 0; t < wall.size(); ++t)
    if (r.source_triangle[t] >= 0) wall[t] = state.wall[std::size_t(r.source_triangle[t])];
  std::vector<Vec3d> probe = r.binding_probe;
  // Input vertices keep their index: keep the probe an earlier cut gave them unless this split moved it off
  // this cut (a vertex lying on the new swept surface).
  for (std::size_t v = 0; v < state.mesh.vertices.size(); ++v)
    if (norm(r.binding_probe[v] - state.mesh.vertices[v]) == 0.0) probe[v] = state.probe[v];
  state.mesh = r.mesh;
  state.wall = std::move(wall);
  state.probe = std::move(probe);
  state.checked = true;
  ++state.splits;
  return r;
}

namespace {
struct Box {
  Vec3d lo, hi;
};
Box boxOf(const SweptSurface& s) {
  Box b{s.vertices.front(), s.vertices.front()};
  for (const auto& v : s.vertices)
    for (int a = 0; a < 3; ++a) b.lo[a] = std::min(b.lo[a], v[a]), b.hi[a] = std::max(b.hi[a], v[a]);
  return b;
}
}  // namespace

SkinBinding bindSkinAcrossCuts(const CutSurfaceState& state, const MetaballModel& spheres,
                               const std::vector<SweptSurface>& cuts, int k, const std::string& file) {
  std::vector<Box> boxes;
  for (const auto& c : cuts) boxes.push_back(boxOf(c));
  std::vector<SweptSurfaceQuery> queries;  // the same decisions as segmentCrossesSweptSurface, triangles pre-boxed
  queries.reserve(cuts.size());
  for (const auto& c : cuts) queries.emplace_back(c);
  const SkinFilter sees = [&](int v, int sphere) {
    const Vec3d& p = state.probe[std::size_t(v)];
    const Vec3d& q = spheres.rest_centers[std::size_t(sphere)];
    for (std::size_t c = 0; c < cuts.size(); ++c) {
      bool apart = false;  // the segment's box misses the cut's box: no crossing possible
      for (int a = 0; a < 3 && !apart; ++a)
        apart = std::max(p[a], q[a]) < boxes[c].lo[a] || std::min(p[a], q[a]) > boxes[c].hi[a];
      if (!apart && queries[c].segmentCrosses(p, q)) return false;
    }
    return true;
  };
  return bindSkin(state.mesh, spheres, k, file, sees);
}

}  // namespace inc
