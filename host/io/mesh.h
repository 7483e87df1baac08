// Triangle surface meshes: the data, loading (OBJ/PLY/STL), writing, and validity checks.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "physics/vec3.h"

namespace inc {

struct TriangleMesh {
  std::vector<Vec3d> vertices;                // metres (scene units)
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise seen from outside when closed
};

// Topology and geometry facts about a mesh; computed once on load, never in a hot loop.
struct MeshReport {
  int vertex_count = 0;
  int triangle_count = 0;
  int boundary_edges = 0;        // edges with one incident triangle (open mesh)
  int non_manifold_edges = 0;    // edges with more than two incident triangles
  int inconsistent_edges = 0;    // interior edges traversed in the same direction by both triangles
  int degenerate_triangles = 0;  // zero area or repeated vertex index
  int components = 0;            // connected components over shared vertices
  double signed_volume = 0.0;    // divergence theorem; > 0 when outward oriented
  double area = 0.0;
  Vec3d bbox_min, bbox_max;
  bool closed() const { return boundary_edges == 0 && non_manifold_edges == 0; }
  bool watertight() const { return closed() && inconsistent_edges == 0 && degenerate_triangles == 0; }
};

// Loads by extension (.obj, .ply ascii/binary, .stl ascii/binary). Throws InputError naming the file,
// the element (e.g. "vertex 12", "face 7") and the reason: unreadable, empty, NaN vertex, bad index.
TriangleMesh loadMesh(const std::string& path);

MeshReport analyzeMesh(const TriangleMesh& mesh);

// Throws InputError(file, key, reason) unless the mesh is closed, manifold, consistently oriented and
// of positive volume; flips a consistently inward-oriented mesh in place (and says so via the return).
// Returns a note describing any repair made ("" when none).
std::string requireClosedMesh(TriangleMesh& mesh, const std::string& file, const std::string& key);

void writeObj(const std::string& path, const TriangleMesh& mesh);

}  // namespace inc
