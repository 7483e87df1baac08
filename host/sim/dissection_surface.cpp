// The dissection's surface: its skin, the opening shown while the blade is in, and the wall flags.
// The skin carries it on the spheres and, during a stroke, on the points of the cut spheres.
#include <algorithm>

#include "host/assembly/skin_binding.h"
#include "host/sim/dissection_simulation_impl.h"

namespace inc::dissection {

// Binds the surface to the spheres. After a cut each vertex binds only to spheres it sees without crossing
// any cut (no skin weight across a swept surface; host/cut/cut_surface_state.h).
template <typename T>
void DissectionSimulation<T>::bindSurface() {
  skin_rest_centres_ = spheres_.rest_centers;
  const int k = std::min<int>(4, int(spheres_.size()));
  const SkinBinding b = earlier_cuts_.empty() ? bindSkin(rest_surface_, spheres_, k, scene_.file)
                                              : bindSkinAcrossCuts(*surface_, spheres_, earlier_cuts_, k, scene_.file);
  skin_ = Skin{b.k, b.rest_vertices, b.sphere, b.weight};
}

// The displacement of skin sphere s (an index of the model the skin was bound to: during a stroke, the
// stroke's base) seen from rest vertex p.
template <typename T>
Vec3d DissectionSimulation<T>::skinSphereDisplacement(std::int32_t s, const Vec3d& p) const {
  std::int32_t i = s;
  if (active_) {
    Vec3d u;
    if (active_->region && active_->region->role(s) == SphereRole::Cut && active_->region->sphereDisplacement(s, p, u))
      return u;
    i = active_->base_to_pbd[std::size_t(s)];
    if (i < 0) return Vec3d();
  }
  return Vec3d(state_.positions[std::size_t(i)]) - skin_rest_centres_[std::size_t(s)];
}

// Translation skinning: v = v0 + sum_j w_j u_j over the vertex's bound spheres, u_j the sphere's displacement;
// during a stroke a converted sphere's displacement is eq. 13 over its points (the piece nearest the vertex).
// While a stroke's surface opening is shown (cutting.open_surface_frames), its mesh and skin instead.
template <typename T>
bool DissectionSimulation<T>::currentSurface(TriangleMesh& out) const {
  const OpenedSurface* opened = opening_.shown();
  const Skin& skin = opened ? opened->skin : skin_;
  out = opened ? opened->mesh : rest_surface_;
  const int k = skin.k;
  for (std::size_t v = 0; v < out.vertices.size(); ++v) {
    Vec3d d;
    for (int j = 0; j < k; ++j)
      d += skinSphereDisplacement(skin.sphere[v * k + j], skin.rest_vertices[v]) * skin.weight[v * k + j];
    out.vertices[v] = skin.rest_vertices[v] + d;
  }
  return true;
}

template <typename T>
void DissectionSimulation<T>::cutWallTriangles(std::vector<std::uint8_t>& out) const {
  const OpenedSurface* opened = opening_.shown();
  out = opened ? opened->wall : wall_flags_;
}

// At a frame's start, when no opening is in the making and the sweep grew since the last one: a worker splits
// the surface as it was before the stroke along the sweep so far (a slit ending where the blade is) and binds the
// skin of the split surface to the stroke's base spheres across every cut including the partial sweep, so each
// side of the slit follows its own spheres and, through cut spheres, the piece of their points on its side
// (skinSphereDisplacement). It is shown from the start of the frame open_surface_frames frames later until the
// next one or the stroke's end, which splits the surface before the stroke along the whole sweep as without it:
// display only, no simulated result changes. A split the sweep so far does not allow leaves the last one shown.
template <typename T>
void DissectionSimulation<T>::openSurface(double t0) {
  const int n = scene_.cutting.open_surface_frames;
  if (n <= 0 || opening_.inMaking() || !active_ || ending_) return;
  ActiveStroke& a = *active_;
  if (a.swept.triangles.empty() || a.swept.triangles.size() == a.opened_triangles) return;
  a.opened_triangles = a.swept.triangles.size();
  std::vector<SweptSurface> cuts = earlier_cuts_;
  cuts.push_back(a.swept);
  opening_.start(t0, n, std::move(cuts), a.base, surface_, scene_.file);
}

// This file's members for the two precisions makeDissectionSimulation builds.
#define INC_DISSECTION_SURFACE(T)                                                                   \
  template void DissectionSimulation<T>::bindSurface();                                             \
  template Vec3d DissectionSimulation<T>::skinSphereDisplacement(std::int32_t, const Vec3d&) const; \
  template bool DissectionSimulation<T>::currentSurface(TriangleMesh&) const;                       \
  template void DissectionSimulation<T>::cutWallTriangles(std::vector<std::uint8_t>&) const;        \
  template void DissectionSimulation<T>::openSurface(double);
INC_DISSECTION_SURFACE(float)
INC_DISSECTION_SURFACE(double)
#undef INC_DISSECTION_SURFACE

}  // namespace inc::dissection
