// The visibility-filtered MLS supports of one stroke's nodal points, kept up to date across the stroke.
#pragma once

#include <cstdint>
#include <vector>

#include "host/cut/cut_swept_surface.h"
#include "model/neighbor_lists.h"
#include "physics/vec3.h"

namespace inc {

// The lists visibleSupports (host/cut/cut_nodal_points.h) gives for the points and the cuts (the earlier cuts and the
// stroke so far), updated as points are appended and the stroke grows instead of recomputed: a conversion then
// costs in the new points and the new strip, not in every point. The result is the same lists bit for bit
// (offsets, indices, order) and the same count of dropped entries; tests/cut/test_cut_stroke_supports.cpp compares
// them over scripted strokes.
//
// Why it is exact: visibleSupports drops a pair (a < b, |x_a - x_b| <= h) when, for some cut c, both ends lie
// within `reach` of c and segment x_a-x_b crosses c. A swept surface's distance is the least over its triangles
// and its crossing any triangle's, each decided from that triangle's own vertices, so for the stroke S0 + F
// (F the new strip) "near S0 + F" is "near S0 or near F" and "crosses S0 + F" is "crosses S0 or crosses F". A
// pair kept before stays kept unless both ends are near the grown stroke and it crosses it; when both were near
// S0 already it did not cross S0, so F alone decides. visibleSupports' box filter (a cut skipped when its box
// misses the points' box grown by h) never changes a decision: a crossing segment overlaps the triangle's box,
// widened by far less than h.
//
// Serial: an update is well under a millisecond of work, less than what OpenMP regions cost on a loaded two-core
// machine (measured at load average 3-4: a strip pass with three parallel regions 36 ms, serial 0.5 ms).
class StrokeSupports {
 public:
  StrokeSupports() = default;
  // h (m): the support radius. `earlier_cuts`: cuts applied before this stroke, kept by pointer (they must
  // outlive this object).
  StrokeSupports(double support_radius, std::vector<const SweptSurface*> earlier_cuts);

  // `x`: every point, those already listed first and unchanged, then the new ones. `stroke`: the stroke so far.
  // When it extends the stroke seen so far (its first triangles are the ones applied), only its new triangles
  // are applied to the listed pairs and the new points get their lists; otherwise everything is recomputed.
  void update(const std::vector<Vec3d>& x, const SweptSurface& stroke);
  // The stroke grew by the strip `fresh` (its new triangles alone), the points did not change: the pairs that
  // now cross the stroke are dropped. Returns how many directed entries.
  std::size_t extend(const std::vector<Vec3d>& x, const SweptSurface& fresh);

  const NeighborLists& lists() const { return lists_; }
  std::size_t pointCount() const { return lists_.queryCount(); }
  std::size_t removed() const { return removed_; }  // directed entries dropped so far (visibleSupports' count)
  void clear();

 private:
  std::size_t applyStrip(const std::vector<Vec3d>& x, const SweptSurface& fresh);
  void appendPoints(const std::vector<Vec3d>& x);
  NeighborLists newRows(const std::vector<Vec3d>& x, std::size_t n0) const;
  bool crosses(const std::vector<Vec3d>& x, std::size_t a, std::size_t b, const std::vector<SweptSurfaceQuery>& earlier,
               const SweptSurfaceQuery& stroke) const;
  void mergeRows(const NeighborLists& rows, const std::vector<char>& keep);
  bool extendsStroke(const SweptSurface& stroke) const;

  double h_ = 0.0, reach_ = 0.0;  // m; reach: visibleSupports' "near a cut" distance
  std::vector<const SweptSurface*> earlier_;
  SweptSurface stroke_;                                   // the stroke's triangles applied so far (own copy)
  NeighborLists lists_, spare_;                           // spare_: mergeRows' output buffer, swapped with lists_
  std::vector<std::vector<std::uint32_t>> near_earlier_;  // per point: the earlier cuts within reach
  std::vector<char> near_stroke_;                         // per point: within reach of stroke_
  std::size_t removed_ = 0;
};

}  // namespace inc
