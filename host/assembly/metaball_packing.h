// Sphere packing of a closed surface mesh into a metaball organ (greedy medial-ball cover), with coverage report and
// cache.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "host/assembly/metaball_model.h"
#include "host/io/mesh.h"
#include "host/io/mesh_self_intersection.h"

namespace inc {

struct PackingOptions {
  int target_spheres = 550;       // spheres placed at most (the paper's liver: 570); the cover stops earlier
                                  // only when every interior sample is covered or stop_coverage is reached
  double stop_coverage = 1.0;     // stop once this fraction of the interior samples is covered
  int samples = 40000;            // approximate number of interior grid samples (sets the grid spacing h)
  double max_protrusion = 0.01;   // farthest a sphere may reach beyond the surface, fraction of the bbox diagonal
  double density_kg_m3 = 1060.0;  // tissue density; masses = density * volume share (power cell)
  double max_self_intersecting_fraction = kToleratedSelfIntersectingFraction;  // see preparePackInput
  // The key that errors about the mesh name (a scene's: "geometry.mesh"); not part of the cache key.
  std::string mesh_key = "mesh";
  // Progress (stage name, fraction in [0, 1]); not part of the cache key. May be empty.
  std::function<void(const char* stage, double fraction)> progress;
};

struct PackReport {
  int spheres = 0;
  int links = 0;                // overlapping pairs
  int components = 0;           // connected components of the overlap graph (1 for a connected organ; one per
                                // separate shell of a multi-shell mesh)
  int bridged = 0;              // spheres grown to join a detached group to the rest
  int stragglers_linked = 0;    // spheres of groups still detached after that, joined by links inside the mesh
  int dropped = 0;              // spheres of detached groups no link could join, removed (their interior is
                                // weighed to the spheres kept)
  double mesh_volume = 0.0;     // enclosed volume, mesh units^3
  double sample_spacing = 0.0;  // grid spacing h, mesh units
  double coverage = 0.0;        // fraction of interior points (grid staggered by h/2 against the packing grid)
                                // inside the sphere union
  double surface_mean = 0.0;    // mesh surface -> union boundary, mean |min_i(|p - c_i| - r_i)| over vertices and
  double surface_max = 0.0;     //   triangle centroids (exact outside the union, a lower bound inside)
  double union_mean = 0.0;      // union boundary -> mesh surface: mean and max |signed distance| of points on
  double union_max = 0.0;       //   sphere surfaces not inside another sphere
  double max_protrusion = 0.0;  // max_i (r_i + sdf(c_i)): how far a sphere reaches beyond the surface
  double mean_overlap = 0.0;    // mean over links of (r_i + r_j - d_ij) / min(r_i, r_j)
  double mean_degree = 0.0;     // mean links per sphere
  double seconds = 0.0;         // packing time (0 when loaded from the cache)
  bool from_cache = false;
  std::uint64_t key = 0;  // cache key (mesh + options)
  std::string repairs;    // input repairs made or tolerated (see preparePackInput), "" when none
};

struct PackedOrgan {
  MetaballModel model;
  PackReport report;
};

// Fills the interior of a closed surface with overlapping spheres; deterministic (same mesh and options give
// bit-identical output for any thread count). Throws InputError(file, "mesh" or "packing.<option>", reason)
// for a bad mesh (open, non-manifold, inconsistent, zero volume, self-intersecting beyond the tolerance) or
// bad options.
PackedOrgan packOrgan(const TriangleMesh& mesh, const PackingOptions& options, const std::string& file = "");

// Hash (FNV-1a, 64 bit) of the mesh's coordinates and indices, the packing options that change the result, and
// the format version.
std::uint64_t packCacheKey(const TriangleMesh& mesh, const PackingOptions& options);

// Loads the pack from `cache_path` when it exists and its key matches; otherwise packs and writes the cache
// (a changed mesh or option invalidates it). An unreadable or corrupt cache is rebuilt, never trusted.
PackedOrgan loadOrBuildPack(const TriangleMesh& mesh, const PackingOptions& options, const std::string& cache_path,
                            const std::string& file = "");

// One human-readable line for the CLI and logs: spheres, links, coverage, deviations, time, repairs.
std::string describePack(const PackReport& report);

// The cache file next to a mesh: "<mesh_path>.pack".
std::string defaultPackCachePath(const std::string& mesh_path);

}  // namespace inc
