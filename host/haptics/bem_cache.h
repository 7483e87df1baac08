// On-disk cache of the BEM global model's precompute: the base inverse A^-1 and the per-element contact table.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "host/haptics/bem_global.h"
#include "host/io/mesh.h"

namespace inc {

// What a cache was built for. The inverse depends on the mesh, the material and the supports; the contact table
// also on the tip's local model (its half-ball radius and node spacing). A cache is used only for exactly these.
struct BemCacheKey {
  std::uint64_t mesh_hash = 0;      // the scaled vertices and triangles, bytewise
  std::uint64_t supports_hash = 0;  // the base conditions, one per element
  std::uint64_t elements = 0;
  double youngs_modulus_pa = 0.0, poisson_ratio = 0.0;
  double local_radius_m = 0.0, local_spacing_m = 0.0;
};
BemCacheKey bemCacheKey(const TriangleMesh& mesh, const std::vector<BemBc>& supports, const Material& material,
                        double local_radius_m, double local_spacing_m);

// The contact table of an organ with E elements (host/haptics/global_organ_model.h): for a tip touching element e,
// stiffness.col(e) is the 3 x 3 force on the organ per tip displacement (world, N/m, column-major) and
// surface.middleCols(3e, 3) the organ's surface displacement per unit force on the organ (3E x 3, world, m/N).
struct OrganContactTable {
  Eigen::MatrixXd stiffness;  // 9 x E
  Eigen::MatrixXd surface;    // 3E x 3E
};

// What readBemCache found: each part is used only when every input it depends on matches and its section's
// checksum is right; `note` says why a part is not (absent file, another mesh / material / supports / local model,
// a truncated or corrupt file), "" when the table was loaded.
struct BemCacheRead {
  bool table = false;    // `table` holds the cached contact table
  bool inverse = false;  // `a_inv` holds the cached base inverse (read only when the table is not usable)
  std::string note;
};
BemCacheRead readBemCache(const std::string& path, const BemCacheKey& key, OrganContactTable& table,
                          Eigen::MatrixXd& a_inv);

// Writes the cache (a temporary file renamed over `path`, so a reader never sees half a file). Throws
// InputError(path, "", reason) when it cannot be written.
void writeBemCache(const std::string& path, const BemCacheKey& key, const OrganContactTable& table,
                   const Eigen::MatrixXd& a_inv);

}  // namespace inc
