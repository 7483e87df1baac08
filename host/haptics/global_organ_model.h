// The hybrid global model of a haptics scene: the BEM organ precomputed (and cached) into a per-element contact
// table, each tool's coupled tip stiffness at the haptic rate, the organ's surface displacement at the visual rate.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "host/haptics/bem_cache.h"
#include "host/haptics/bem_global.h"
#include "host/haptics/cutting_tool.h"
#include "host/haptics/mfs_local.h"
#include "host/haptics/triple_buffer.h"
#include "host/io/mesh.h"

namespace inc {

struct GlobalOrganSetup {
  TriangleMesh mesh;            // metres, checked (loadGlobalOrganMesh)
  std::vector<BemBc> supports;  // one per element (organSupports): held elements carry displacement zero
  Material material;
  HemisphereCloudSpec local;  // the tip's MFS cloud (haptics.local_*)
  std::string cache_path;     // "": no cache
  bool quiet = false;         // no progress bar
  std::string label = "haptics: BEM precompute";
};

// How the precompute went.
struct GlobalOrganPrecompute {
  std::string source;  // "loaded from the cache", "built", "table rebuilt from the cached inverse"
  std::string note;    // why the cache was not used (and a cache that could not be written); "" when loaded
  double seconds = 0.0, assembly_s = 0.0, inverse_s = 0.0, table_s = 0.0;
};

// What hand k's haptic thread publishes each tick for the global step (one triple buffer per hand).
struct OrganContact {
  bool in_contact = false;
  int element = -1;          // the element nearest the tool's anchor
  Vec3d tip_displacement_m;  // tip minus anchor, world
  Vec3d organ_force_n;       // the force the tool applies to the organ, world
};

// The precompute (docs/haptics.md, "Global model in the runner"): the BEM model is assembled and its base inverse
// formed (BemModel::factorBase), then for every element e a HybridHapticModel touch(e) gives the coupled tool
// stiffness K_e (the local MFS half-ball coupled to the organ: F = (I - P S_ac C)^-1 P S_aa u) and the organ's
// surface response S_e to a unit tool force: the OrganContactTable. A held element gets the local model alone
// (the organ does not move there). The table and the inverse are cached at cache_path (bem_cache.h): a cache built
// for exactly this mesh, material, supports and local model is loaded instead, one with only another local model
// rebuilds the table from its inverse, anything else (absent, stale, truncated, corrupt) is rebuilt and rewritten.
// A cache that cannot be written is a note, not an error (the run is right without it).
class GlobalOrganModel {
 public:
  // `hands`: the number of tools (one contact channel each). Throws InputError for a bad mesh or supports (a
  // singular system: an organ part held nowhere).
  GlobalOrganModel(GlobalOrganSetup setup, int hands);

  int elementCount() const { return int(mesh_.triangles.size()); }
  const TriangleMesh& mesh() const { return mesh_; }
  const GlobalOrganPrecompute& precompute() const { return precompute_; }
  const OrganContactTable& table() const { return table_; }
  const std::vector<Vec3d>& centroids() const { return centroids_; }
  int nearestElement(const Vec3d& p) const;

  // The elastic model of hand k's tool (its haptic thread): in contact, the coupled tip stiffness of the element
  // nearest the tool's anchor, -K_e (tip - anchor) on the hand; every tick it publishes the contact for step().
  // No allocation, no lock: an O(E) nearest-element scan when the anchor moves, then a 3 x 3 product.
  CuttingTool::Elastic contactElastic(int hand);

  // Simulation thread, once per frame (the visual rate): the organ's surface displacement for every hand's newest
  // contact, u = sum_k S_(e_k) F_k (superposition: the model is linear), each contact element following its tip.
  void step();
  const Eigen::VectorXd& surfaceDisplacement() const { return u_; }  // 3 per element, world, m
  double maxSurfaceDisplacement_m() const { return max_u_; }
  double peakSurfaceDisplacement_m() const { return peak_u_; }  // the largest of maxSurfaceDisplacement_m so far
  int contacts() const { return contacts_; }
  std::uint64_t steps() const { return steps_; }
  double lastStepSeconds() const { return last_step_s_; }
  // The organ mesh displaced by the last step (each vertex by the mean of its elements' displacements).
  TriangleMesh deformedMesh() const;
  // "global model bem: 80 elements (240 DOFs), loaded from the cache, precompute 0.01 s; 50 steps (one per frame),
  // last step 2.0 us, organ surface max displacement 0 m now, 0.002 m at most" .
  std::string summary() const;

 private:
  void build(const GlobalOrganSetup& setup);
  TriangleMesh mesh_;
  std::vector<Vec3d> centroids_;
  OrganContactTable table_;
  GlobalOrganPrecompute precompute_;
  std::vector<std::unique_ptr<TripleBuffer<OrganContact>>> channels_;
  Eigen::VectorXd u_;
  double max_u_ = 0.0, peak_u_ = 0.0, last_step_s_ = 0.0;
  int contacts_ = 0;
  std::uint64_t steps_ = 0;
};

}  // namespace inc
