// The scalpel's swept surface (the blade segment swept between poses) and the cut decisions made against it.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "model/neighbor_lists.h"
#include "physics/vec3.h"

namespace inc {

// The blade: a segment from `base` to `tip` (m) at one instant.
struct BladePose {
  Vec3d base, tip;
};

// A triangle strip: pose k contributes vertices 2k (base) and 2k+1 (tip); the quad between poses k and k+1 is
// split into triangles (2k, 2k+2, 2k+1) and (2k+1, 2k+2, 2k+3), so every normal is (motion) x (blade) and
// consistently oriented along the strip.
struct SweptSurface {
  std::vector<Vec3d> vertices;
  std::vector<std::array<int, 3>> triangles;
  bool empty() const { return triangles.empty(); }
};

// Throws InputError("cut", "blade", reason) on fewer than 2 poses, a degenerate blade or a non-finite pose.
SweptSurface sweepSurface(const std::vector<BladePose>& poses);
// Appends the strip between the last pose already swept and `next` (the per-frame incremental update).
void extendSweptSurface(SweptSurface& surface, const BladePose& next);

// Visibility criterion: the segment p-q crosses a triangle of the swept surface.
bool segmentCrossesSweptSurface(const SweptSurface& surface, const Vec3d& p, const Vec3d& q);
// The same decision with the triangles' boxes and normals computed once (many segments against one surface), and
// the boxes of runs of kBlock consecutive triangles: a segment that misses a run's box misses each of its
// triangles' boxes, which the per-triangle test rejects anyway, so skipping the run changes no answer.
class SweptSurfaceQuery {
 public:
  explicit SweptSurfaceQuery(const SweptSurface& surface);  // keeps a reference: the surface must outlive it
  bool segmentCrosses(const Vec3d& p, const Vec3d& q) const;
  // The closest swept triangle to p (the lowest index among equally close ones, as the brute-force scan picks)
  // and the closest point on it; -1 for an empty surface. Runs whose box is farther than the best triangle so
  // far are skipped (the boxes are padded far above rounding, so the answer is the brute-force one, bit for bit).
  int closestTriangle(const Vec3d& p, Vec3d& closest) const;
  // distanceToSweptSurface(surface, p), the same bits.
  double distance(const Vec3d& p) const;

 private:
  static constexpr std::size_t kBlock = 8;
  const SweptSurface& s_;
  std::vector<Vec3d> lo_, hi_, n_;
  std::vector<Vec3d> block_lo_, block_hi_;  // per run of kBlock triangles: the union of their boxes
};
// The support pair's visibility test (visibleSupports, StrokeSupports): whether segment xa-xb crosses one of the
// cuts that both of its ends lie near (near_a, near_b: ascending indices into `cuts`).
template <typename Index>
bool crossesACutNearBoth(const std::vector<Index>& near_a, const std::vector<Index>& near_b,
                         const std::vector<SweptSurfaceQuery>& cuts, const Vec3d& xa, const Vec3d& xb) {
  for (std::size_t i = 0, j = 0; i < near_a.size() && j < near_b.size();) {
    if (near_a[i] < near_b[j]) {
      ++i;
    } else if (near_b[j] < near_a[i]) {
      ++j;
    } else {
      if (cuts[near_a[i]].segmentCrosses(xa, xb)) return true;
      ++i, ++j;
    }
  }
  return false;
}

// +1 / -1: the side of p (sign of the oriented normal offset to the closest swept triangle); 0 never returned.
int sideOfSweptSurface(const SweptSurface& surface, const Vec3d& p);
// Unsigned distance from p to the swept surface (m).
double distanceToSweptSurface(const SweptSurface& surface, const Vec3d& p);
// The closest point of the swept surface to p in `closest` and the unit normal of its triangle in `normal`
// (oriented as the strip); returns false for an empty surface.
bool closestOnSweptSurface(const SweptSurface& surface, const Vec3d& p, Vec3d& closest, Vec3d& normal);

// Indices (ascending) of the spheres whose open ball the swept surface enters.
std::vector<std::int32_t> findCutSpheres(const SweptSurface& surface, const std::vector<Vec3d>& centres,
                                         const std::vector<double>& radii);

// Removes from `lists` every pair (q, j) whose segment crosses the swept surface; returns the number removed.
std::size_t removeCrossingNeighbours(NeighborLists& lists, const std::vector<Vec3d>& positions,
                                     const SweptSurface& surface);

// Removes PBD links whose rest segment crosses the swept surface (in place); returns the number removed.
std::size_t removeCrossingLinks(MetaballModel& model, const SweptSurface& surface);

}  // namespace inc
