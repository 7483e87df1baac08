// Global boundary-element model (Kelvin solutions, constant triangles) with a precomputed inverse and SMW updates.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "host/compiled/bem_organ_mesh.h"  // BemBc: an element's boundary condition
#include "host/io/mesh.h"
#include "model/material.h"

namespace inc {

// Sphere meshes for tests and benchmarks: icosahedron subdivided `level` times (20 * 4^level
// triangles); latitude-longitude sphere with `bands` x `segments` (2 * segments * (bands - 1)).
TriangleMesh icosphereMesh(double radius_m, int level);
TriangleMesh uvSphereMesh(double radius_m, int bands, int segments);

// Linear elastostatics on a closed, outward-oriented triangle mesh: piecewise-constant u and t per
// element, collocation at centroids (Brebbia): c u_i + sum_j H^_ij u_j = sum_j G_ij t_j, where
// H_ij = int_j T*(x, x_i) dG, G_ij = int_j U*(x, x_i) dG (3x3 blocks); H_ii (with c) from rigid
// translation. Dense 3E x 3E matrices; assembled once ("offline", with progress callbacks).
class BemModel {
 public:
  using Progress = std::function<void(double fraction)>;
  BemModel(const TriangleMesh& mesh, const Material& material, const Progress& progress = {});

  int elementCount() const { return int(centroids_.size()); }
  const std::vector<Vec3d>& centroids() const { return centroids_; }
  const std::vector<Vec3d>& normals() const { return normals_; }
  const std::vector<double>& areas() const { return areas_; }
  const TriangleMesh& mesh() const { return mesh_; }
  double shearModulus_pa() const { return shear_pa_; }
  double poisson() const { return nu_; }
  // Quadrature of element j (points, weights in m^2 summing to its area): the degree-5 7-point rule on
  // 4^L sub-triangles, L = 0..3 growing as `near_point` gets closer (the rule of the assembly), for
  // integrands that vary like 1 / distance^n from near_point.
  void elementQuadrature(int j, const Vec3d& near_point, std::vector<Vec3d>& points,
                         std::vector<double>& weights) const;
  const Eigen::MatrixXd& H() const { return H_; }
  const Eigen::MatrixXd& G() const { return G_; }
  double assemblySeconds() const { return assembly_s_; }

  // Pure traction problem (all elements loaded): H u = G t with the six rigid modes removed by
  // Lagrange multipliers (u orthogonal to rigid motions). t: 3E tractions (Pa). Returns u (m).
  Eigen::VectorXd solveTractionProblem(const Eigen::VectorXd& t) const;

  // Mixed problem: column j of A is H_j (traction known, u unknown) or -G_j (displacement known).
  // factorBase() inverts A for the base conditions explicitly (O(N^3), the precomputation): an LU, then
  // A^-1 by blocks of columns, reporting the fraction done to `progress` after each block.
  void factorBase(const std::vector<BemBc>& base, const Progress& progress = {});
  // The same from an inverse computed before (a cache, host/haptics/bem_cache.h): A^-1 of `base`, N x N and
  // finite, else InputError.
  void setBaseInverse(const std::vector<BemBc>& base, Eigen::MatrixXd a_inv);
  const Eigen::MatrixXd& baseInverse() const { return a_inv_; }
  double factorSeconds() const { return factor_s_; }
  // Elements switched to displacement BCs relative to the base (the contact). Rank 3k SMW update:
  // Z = A^-1 D, C = I + Z_S (D: column changes); cost O(N^2 k). Throws InputError for bad indices.
  void setContact(const std::vector<int>& contact_elements);
  // Solves with known values: known[3j..3j+2] is t_j for traction elements and u_j for displacement
  // elements (of the current conditions: base + contact). Returns Y (u or t per element, same layout).
  // Uses A_base^-1 and the SMW correction: O(N^2 + N k).
  Eigen::VectorXd solve(const Eigen::VectorXd& known) const;
  // The same for several load cases (one column each): the matrices are read once for all columns.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& known) const;
  // The same by a fresh dense LU of the current A (reference for tests; O(N^3)).
  Eigen::VectorXd solveFresh(const Eigen::VectorXd& known) const;
  std::vector<BemBc> currentBc() const;
  // Displacement at an interior point xi from the boundary solution (Somigliana, c = 1):
  // u(xi) = sum_j G_j(xi) t_j - sum_j H_j(xi) u_j.
  Vec3d interiorDisplacement(const Vec3d& xi, const Eigen::VectorXd& u, const Eigen::VectorXd& t) const;
  // The same as rows: u(xi) = g_rows t - h_rows u (each 3 x 3E), to precompute for fixed points.
  void interiorRows(const Vec3d& xi, Eigen::MatrixXd& g_rows, Eigen::MatrixXd& h_rows) const;

 private:
  Eigen::VectorXd rhs(const Eigen::VectorXd& known, const std::vector<BemBc>& bc) const;
  Eigen::MatrixXd rhs(const Eigen::MatrixXd& known, const std::vector<BemBc>& bc) const;
  Eigen::MatrixXd matrixFor(const std::vector<BemBc>& bc) const;
  TriangleMesh mesh_;
  double shear_pa_, nu_;
  std::vector<Vec3d> centroids_, normals_;
  std::vector<double> areas_;
  Eigen::MatrixXd H_, G_;
  std::vector<BemBc> base_;
  Eigen::MatrixXd a_inv_;
  std::vector<int> contact_;       // element indices switched to displacement
  std::vector<int> changed_cols_;  // 3 per contact element
  Eigen::MatrixXd z_;              // A_base^-1 D
  Eigen::PartialPivLU<Eigen::MatrixXd> c_lu_;
  double assembly_s_ = 0.0, factor_s_ = 0.0;
};

}  // namespace inc
