// Binding of a surface mesh to the spheres of a metaball organ: k nearest spheres per vertex, distance-field weights.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/io/mesh.h"
#include "physics/skinning.h"

namespace inc {

// Rest-state binding (double precision, built once per topology); slots v * k + j.
struct SkinBinding {
  int k = 0;
  std::vector<Vec3d> rest_vertices;
  std::vector<std::int32_t> sphere;
  std::vector<double> weight;
  std::vector<Vec3d> rest_centres;
  // Vertex -> incident triangles (CSR) for the normals; triangle corners flattened, 3 per triangle.
  std::vector<std::int32_t> triangles;
  std::vector<std::int32_t> tri_offsets;  // vertex_count + 1
  std::vector<std::int32_t> tri_of_vertex;
  int vertexCount() const { return int(rest_vertices.size()); }
};

// Binds every vertex to its k spheres of smallest signed distance d_i = |v - c_i| - r_i (ties: lower index),
// with weights skin::bindWeight(d_i - d_min, d_(k+1) - d_min) normalised to sum 1. Uses a uniform grid over the
// centres (exact k-nearest, not approximate). Deterministic. Throws InputError(file, "skinning", reason) for
// k outside [1, 16], no spheres, a non-positive radius, or a triangle index out of range.
SkinBinding bindSkin(const TriangleMesh& surface, const MetaballModel& spheres, int k = 4,
                     const std::string& file = "");
// The same over the spheres `allowed(vertex, sphere)` accepts (e.g. those a vertex sees without crossing a cut:
// no skin weight across the swept surface, section 5.4); a vertex that none is allowed for binds unfiltered.
using SkinFilter = std::function<bool(int vertex, int sphere)>;
SkinBinding bindSkin(const TriangleMesh& surface, const MetaballModel& spheres, int k, const std::string& file,
                     const SkinFilter& allowed);

// The binding in precision T, owning its arrays; view() gives the pointers the kernels and CPU loops use.
template <typename T>
struct SkinArrays {
  int k = 0;
  std::vector<Vec3<T>> rest_vertices, rest_centres;
  std::vector<std::int32_t> sphere;
  std::vector<T> weight;
  std::vector<std::int32_t> triangles, tri_offsets, tri_of_vertex;
  skin::SkinView<T> view() const {
    skin::SkinView<T> v;
    v.vertex_count = int(rest_vertices.size());
    v.k = k;
    v.rest_vertices = rest_vertices.data();
    v.sphere = sphere.data();
    v.weight = weight.data();
    v.rest_centres = rest_centres.data();
    return v;
  }
};

template <typename T>
SkinArrays<T> skinArrays(const SkinBinding& b);

// Sphere neighbourhoods for the per-sphere rotation estimate (skin::sphereRotation): CSR of linked spheres.
template <typename T>
struct SphereNeighbourhoods {
  std::vector<std::int32_t> offsets;     // size() + 1
  std::vector<std::int32_t> neighbours;  // ascending per sphere
  std::vector<T> masses;
  std::vector<Vec3<T>> rest_centres;
};

// Throws InputError("metaball model", "links", reason) for a link index out of range or masses of the wrong size.
template <typename T>
SphereNeighbourhoods<T> sphereNeighbourhoods(const MetaballModel& mb);

}  // namespace inc
