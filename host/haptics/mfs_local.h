// Local model of the method of finite spheres around the tool tip: MLS nodes, stiffness, condensation (eq. 6).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "model/material.h"
#include "physics/vec3.h"

namespace inc {

// Nodes (each the centre of a sphere of radius support_m) and the quadrature of the covered volume.
struct MfsCloud {
  std::vector<Vec3d> nodes;            // metres
  std::vector<double> support_m;       // sphere radius of each node
  std::vector<std::uint8_t> singular;  // 1: eq. 5 singular weight (tool-tip / contact nodes)
  std::vector<Vec3d> quad_points;      // metres
  std::vector<double> quad_weights_m3;
};

// A graded half-ball of tissue below the surface z = 0, centred on the tool tip at the origin: one
// node at the tip, then hemispherical shells at radius i * inner_spacing for i <= inner_shells and
// then spacing growing by `growth` up to radius_m; on each shell, latitude rings from the bottom pole
// to the surface ring (z = 0) with nodes about one shell gap apart, so every sphere (support =
// support_factor * local gap) stays round and covers a few dozen nodes. Gauss points (gauss^3 per
// cell in r, polar angle, azimuth) integrate the half-ball. Throws InputError for a bad spec.
struct HemisphereCloudSpec {
  double inner_spacing_m = 1e-3;
  int inner_shells = 2;
  double radius_m = 5e-3;
  double growth = 1.5;
  int gauss = 2;
  double support_factor = 2.0;
};
struct HemisphereCloud {
  MfsCloud cloud;
  std::vector<double> shell_r_m;  // shell radii (shell 0: the tip node)
  std::vector<int> node_shell;
  std::vector<std::uint8_t> node_surface;  // 1: on the surface z = 0
};
HemisphereCloud hemisphereCloud(const HemisphereCloudSpec& spec);

// MLS shape functions (eqs. 1-3, P = (1, x, y, z)) of all nodes whose sphere covers x: indices, values
// and gradients. Returns false when fewer than 4 non-coplanar nodes cover x (moment matrix singular).
struct ShapeValues {
  std::vector<int> index;
  std::vector<double> h;
  std::vector<Vec3d> grad_h;
};
bool mlsShapeFunctions(const MfsCloud& cloud, const Vec3d& x, int singular_p, ShapeValues& out);

enum class DofRole : std::uint8_t {
  kFree = 0,        // U_b: solved for
  kPrescribed = 1,  // U_a: the tool (tip node, punch face): prescribed displacement, reaction wanted
  kCoupled = 2,     // U_c: prescribed by the surroundings (0 = fixed, or the global model's displacement)
};

// Linear elastic local model. The stiffness is assembled once from the cloud (Galerkin with the MLS
// gradients, see docs/haptics.md for why not point collocation); setRoles() partitions the DOFs and
// factorises K_bb (when the contact region changes); each haptic tick is then reactionForce(): two
// small dense matrix-vector products.
class MfsLocalModel {
 public:
  static constexpr int kSingularPower = 2;  // p of eq. 5
  MfsLocalModel(MfsCloud cloud, const Material& material);
  ~MfsLocalModel();

  // dof_roles: one per DOF (3 per node, x y z). Factorises K_bb (sparse LDLT) and precomputes the
  // condensed operators S_aa = K_aa + K_ab G_a, S_ac = K_ac + K_ab G_c, G_* = -K_bb^-1 K_b*.
  // coupled_moves = false: the coupled DOFs stay fixed at zero (skips the K_bb^-1 K_bc solves).
  void setRoles(const std::vector<DofRole>& dof_roles, bool coupled_moves = true);
  // Per tick (eq. 6): f_a = S_aa U_a + S_ac U_c, the force (N) the tool applies at its DOFs; the
  // tissue pushes back on the tool with -f_a.
  Eigen::VectorXd reactionForce(const Eigen::VectorXd& u_a, const Eigen::VectorXd& u_c) const;
  // U_b = G_a U_a + G_c U_c (for display; not needed for the force).
  Eigen::VectorXd freeDisplacement(const Eigen::VectorXd& u_a, const Eigen::VectorXd& u_c) const;

  const MfsCloud& cloud() const { return cloud_; }
  int dofCount() const { return 3 * int(cloud_.nodes.size()); }
  const std::vector<int>& prescribedDofs() const { return a_; }
  const std::vector<int>& coupledDofs() const { return c_; }
  const std::vector<int>& freeDofs() const { return b_; }
  // The condensed operators of the current roles (eq. 6): f_a = S_aa U_a + S_ac U_c.
  const Eigen::MatrixXd& condensedAA() const { return s_aa_; }
  const Eigen::MatrixXd& condensedAC() const { return s_ac_; }
  double assemblySeconds() const { return assembly_s_; }
  double factorSeconds() const { return factor_s_; }
  // x K x for a displacement of all DOFs (twice the strain energy, J): for tests.
  double energyNorm(const Eigen::VectorXd& u) const;

 private:
  struct Impl;
  MfsCloud cloud_;
  Material material_;
  std::unique_ptr<Impl> impl_;
  std::vector<int> a_, b_, c_;
  Eigen::MatrixXd s_aa_, s_ac_, g_a_, g_c_;
  double assembly_s_ = 0.0, factor_s_ = 0.0;
};

// The tip tool's local model: the cloud of `spec` with the tip node's singular weight (eq. 5), its x, y, z
// prescribed and the outer shell coupled (held at zero when coupled_moves is false), factorised once.
std::shared_ptr<MfsLocalModel> mfsTipModel(const HemisphereCloudSpec& spec, const Material& material,
                                           bool coupled_moves = true);

}  // namespace inc
