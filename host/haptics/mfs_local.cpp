// Method of finite spheres: cloud generation, MLS shape functions, Galerkin stiffness, condensation.
#include "host/haptics/mfs_local.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "host/compiled/material_checks.h"
#include "model/input_error.h"
#include "physics/mls_weight.h"

namespace inc {

namespace {
double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<double> gradedCoordinates(double h, int inner, double extent, double growth) {
  std::vector<double> c{0.0};
  for (int i = 1; i <= inner && i * h < extent * (1.0 - 1e-9); ++i) c.push_back(i * h);
  double step = h;
  while (c.back() < extent * (1.0 - 1e-9)) {
    step *= growth;
    double next = c.back() + step;
    if (next > extent || extent - next < 0.5 * step) next = extent;
    c.push_back(next);
  }
  return c;
}

void gaussLegendre(int n, std::vector<double>& x, std::vector<double>& w) {  // on [0, 1]
  if (n == 1) {
    x = {0.5};
    w = {1.0};
    return;
  }
  if (n == 2) {
    const double d = 0.5 / std::sqrt(3.0);
    x = {0.5 - d, 0.5 + d};
    w = {0.5, 0.5};
    return;
  }
  const double d = 0.5 * std::sqrt(0.6);
  x = {0.5 - d, 0.5, 0.5 + d};
  w = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
}
}  // namespace

HemisphereCloud hemisphereCloud(const HemisphereCloudSpec& s) {
  const char* f = "<mfs cloud>";
  if (!(s.inner_spacing_m > 0.0) || !std::isfinite(s.inner_spacing_m))
    throw InputError(f, "inner_spacing_m", "must be > 0");
  if (s.inner_shells < 1) throw InputError(f, "inner_shells", "must be >= 1");
  if (!(s.radius_m >= s.inner_spacing_m) || !std::isfinite(s.radius_m))
    throw InputError(f, "radius_m", "must be at least the inner spacing");
  if (!(s.growth >= 1.0) || s.growth > 3.0) throw InputError(f, "growth", "must be in [1, 3]");
  if (s.gauss < 1 || s.gauss > 3) throw InputError(f, "gauss", "must be 1, 2 or 3");
  if (!(s.support_factor >= 1.2) || s.support_factor > 5.0)
    throw InputError(f, "support_factor", "must be in [1.2, 5]");

  HemisphereCloud out;
  out.shell_r_m = gradedCoordinates(s.inner_spacing_m, s.inner_shells, s.radius_m, s.growth);
  const int ns = int(out.shell_r_m.size());
  auto gapOf = [&](int i) {
    double g = 0.0;
    if (i > 0) g = std::max(g, out.shell_r_m[i] - out.shell_r_m[i - 1]);
    if (i + 1 < ns) g = std::max(g, out.shell_r_m[i + 1] - out.shell_r_m[i]);
    return g;
  };
  // Latitude rings on shell i: psi from the downward axis (0) to the surface (pi/2), spacing ~ gap.
  auto latitudes = [&](int i) { return std::max(1, int(std::lround(0.5 * M_PI * out.shell_r_m[i] / gapOf(i)))); };
  auto around = [&](double circumference, double gap) { return std::max(1, int(std::lround(circumference / gap))); };
  MfsCloud& cl = out.cloud;
  auto addNode = [&](const Vec3d& x, double support, int shell, bool surface) {
    cl.nodes.push_back(x);
    cl.support_m.push_back(support);
    cl.singular.push_back(0);
    out.node_shell.push_back(shell);
    out.node_surface.push_back(surface ? 1 : 0);
  };
  addNode({0.0, 0.0, 0.0}, s.support_factor * gapOf(0), 0, true);  // the tool tip
  for (int i = 1; i < ns; ++i) {
    const double r = out.shell_r_m[i], g = gapOf(i);
    const int m = latitudes(i);
    for (int l = 0; l <= m; ++l) {
      const double psi = 0.5 * M_PI * l / m;
      const int n = l == 0 ? 1 : std::max(3, around(2.0 * M_PI * r * std::sin(psi), g));
      for (int j = 0; j < n; ++j) {
        const double phi = 2.0 * M_PI * (j + 0.5 * ((i + l) % 2)) / n;
        const double rho = r * std::sin(psi);
        addNode({rho * std::cos(phi), rho * std::sin(phi), l == m ? 0.0 : -r * std::cos(psi)}, s.support_factor * g, i,
                l == m);
      }
    }
  }
  std::vector<double> gx, gw;
  gaussLegendre(s.gauss, gx, gw);
  for (int i = 0; i + 1 < ns; ++i) {
    const double r0 = out.shell_r_m[i], r1 = out.shell_r_m[i + 1], g = r1 - r0;
    const int m = latitudes(i + 1);
    for (int l = 0; l < m; ++l) {
      const double p0 = 0.5 * M_PI * l / m, p1 = 0.5 * M_PI * (l + 1) / m;
      const int n = std::max(3, around(2.0 * M_PI * r1 * std::sin(0.5 * (p0 + p1)), g));
      for (int j = 0; j < n; ++j)
        for (int a = 0; a < s.gauss; ++a)
          for (int b = 0; b < s.gauss; ++b)
            for (int c = 0; c < s.gauss; ++c) {
              const double r = r0 + g * gx[a], psi = p0 + (p1 - p0) * gx[b], phi = 2.0 * M_PI * (j + gx[c]) / n;
              const double rho = r * std::sin(psi);
              cl.quad_points.push_back({rho * std::cos(phi), rho * std::sin(phi), -r * std::cos(psi)});
              // volume element r^2 sin(psi) dr dpsi dphi
              cl.quad_weights_m3.push_back(gw[a] * gw[b] * gw[c] * g * (p1 - p0) * (2.0 * M_PI / n) * r * r *
                                           std::sin(psi));
            }
    }
  }
  return out;
}

namespace {
// Shape functions at x given the covering nodes; basis centred at x (the MLS shape functions do not
// depend on the affine frame of P, so derivatives taken with the centre frozen are exact).
bool shapeAt(const MfsCloud& cl, const Vec3d& x, int singular_p, const std::vector<int>& cand, ShapeValues& out) {
  out.index.clear();
  out.h.clear();
  out.grad_h.clear();
  std::vector<double> w;
  std::vector<Vec3d> gw;
  double scale = 0.0;
  for (int J : cand) {
    Vec3d g;
    const double wj = mfsWeight(x, cl.nodes[J], cl.support_m[J], cl.singular[J] ? singular_p : 0, &g);
    if (wj <= 0.0) continue;
    out.index.push_back(J);
    w.push_back(wj);
    gw.push_back(g);
    scale = std::max(scale, cl.support_m[J]);
  }
  if (out.index.size() < 4) return false;
  const int n = int(out.index.size());
  std::vector<Eigen::Vector4d> p(n);
  for (int q = 0; q < n; ++q) {
    const Vec3d d = (cl.nodes[out.index[q]] - x) * (1.0 / scale);
    p[q] = Eigen::Vector4d(1.0, d.x, d.y, d.z);
  }
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  Eigen::Matrix4d dA[3] = {Eigen::Matrix4d::Zero(), Eigen::Matrix4d::Zero(), Eigen::Matrix4d::Zero()};
  for (int q = 0; q < n; ++q) {
    const Eigen::Matrix4d pp = p[q] * p[q].transpose();
    A += w[q] * pp;  // eq. 3
    for (int k = 0; k < 3; ++k) dA[k] += gw[q][k] * pp;
  }
  const Eigen::FullPivLU<Eigen::Matrix4d> lu(A);
  if (lu.rank() < 4 || lu.rcond() < 1e-12) return false;
  const Eigen::Vector4d px(1.0, 0.0, 0.0, 0.0);
  const Eigen::Vector4d gamma = lu.solve(px);
  Eigen::Vector4d dgamma[3];
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector4d dp = Eigen::Vector4d::Zero();
    dp[k + 1] = 1.0 / scale;
    dgamma[k] = lu.solve(dp - dA[k] * gamma);
  }
  out.h.resize(n);
  out.grad_h.resize(n);
  for (int q = 0; q < n; ++q) {
    const double gp = gamma.dot(p[q]);
    out.h[q] = w[q] * gp;  // eq. 2
    for (int k = 0; k < 3; ++k) out.grad_h[q][k] = gw[q][k] * gp + w[q] * dgamma[k].dot(p[q]);
  }
  return true;
}

std::vector<int> coveringNodes(const MfsCloud& cl, const Vec3d& x) {
  std::vector<int> c;
  for (int J = 0; J < int(cl.nodes.size()); ++J)
    if (norm2(x - cl.nodes[J]) < cl.support_m[J] * cl.support_m[J]) c.push_back(J);
  return c;
}
}  // namespace

bool mlsShapeFunctions(const MfsCloud& cloud, const Vec3d& x, int singular_p, ShapeValues& out) {
  return shapeAt(cloud, x, singular_p, coveringNodes(cloud, x), out);
}

struct MfsLocalModel::Impl {
  Eigen::SparseMatrix<double> K;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
};

MfsLocalModel::MfsLocalModel(MfsCloud cloud, const Material& material)
    : cloud_(std::move(cloud)), material_(material), impl_(std::make_unique<Impl>()) {
  const char* f = "<mfs model>";
  validateMaterial(material_, f);  // E and nu (the local model uses no density or damping)
  const int N = int(cloud_.nodes.size());
  if (N < 4 || cloud_.support_m.size() != std::size_t(N) || cloud_.singular.size() != std::size_t(N) ||
      cloud_.quad_points.size() != cloud_.quad_weights_m3.size())
    throw InputError(f, "cloud", "inconsistent node/quadrature arrays");
  const auto t0 = std::chrono::steady_clock::now();
  const double E = material_.youngs_modulus_pa, nu = material_.poisson_ratio;
  const double lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), mu = E / (2.0 * (1.0 + nu));

  for (int J = 0; J < N; ++J)
    if (!(cloud_.support_m[J] > 0.0) || !isFinite(cloud_.nodes[J])) throw InputError(f, "support_m", "must be > 0");
  // Node-pair blocks: a dense 3x3 per coupled pair, accumulated through a per-row sorted index.
  std::vector<std::vector<int>> cols(N);
  std::vector<std::vector<double>> blocks(N);
  auto blockOf = [&](int I, int J) -> double* {
    auto& c = cols[I];
    auto it = std::lower_bound(c.begin(), c.end(), J);
    const std::size_t pos = std::size_t(it - c.begin());
    if (it == c.end() || *it != J) {
      c.insert(it, J);
      blocks[I].insert(blocks[I].begin() + std::ptrdiff_t(9 * pos), 9, 0.0);
    }
    return &blocks[I][9 * pos];
  };
  ShapeValues sv;
  std::vector<int> cand;
  for (std::size_t q = 0; q < cloud_.quad_points.size(); ++q) {
    const Vec3d& x = cloud_.quad_points[q];
    cand.clear();
    for (int J = 0; J < N; ++J)
      if (norm2(x - cloud_.nodes[J]) < cloud_.support_m[J] * cloud_.support_m[J]) cand.push_back(J);
    if (!shapeAt(cloud_, x, kSingularPower, cand, sv))
      throw InputError(f, "quadrature point " + std::to_string(q), "fewer than 4 non-coplanar nodes cover it");
    const double wq = cloud_.quad_weights_m3[q];
    const int n = int(sv.index.size());
    for (int i = 0; i < n; ++i) {
      const Vec3d gi = sv.grad_h[i];
      for (int j = 0; j < n; ++j) {
        const Vec3d gj = sv.grad_h[j];
        double* B = blockOf(sv.index[i], sv.index[j]);
        const double gg = dot(gi, gj);
        // K_IJ_ab = w (lambda d_a h_I d_b h_J + mu d_b h_I d_a h_J + mu delta_ab grad h_I . grad h_J)
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            B[3 * a + b] += wq * (lambda * gi[a] * gj[b] + mu * gi[b] * gj[a] + (a == b ? mu * gg : 0.0));
      }
    }
  }
  std::vector<Eigen::Triplet<double>> trip;
  for (int I = 0; I < N; ++I)
    for (std::size_t c = 0; c < cols[I].size(); ++c)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) trip.emplace_back(3 * I + a, 3 * cols[I][c] + b, blocks[I][9 * c + 3 * a + b]);
  impl_->K.resize(3 * N, 3 * N);
  impl_->K.setFromTriplets(trip.begin(), trip.end());
  assembly_s_ = secondsSince(t0);
}

MfsLocalModel::~MfsLocalModel() = default;

void MfsLocalModel::setRoles(const std::vector<DofRole>& roles, bool coupled_moves) {
  const int n = dofCount();
  if (int(roles.size()) != n) throw InputError("<mfs model>", "dof_roles", "need one role per DOF");
  const auto t0 = std::chrono::steady_clock::now();
  a_.clear();
  b_.clear();
  c_.clear();
  std::vector<int> local(n);
  for (int d = 0; d < n; ++d) {
    auto& v = roles[d] == DofRole::kFree ? b_ : (roles[d] == DofRole::kPrescribed ? a_ : c_);
    local[d] = int(v.size());
    v.push_back(d);
  }
  if (a_.empty()) throw InputError("<mfs model>", "dof_roles", "no prescribed (tool) DOF");
  if (c_.empty()) throw InputError("<mfs model>", "dof_roles", "no coupled DOF: the local block would float");
  // Extract K_bb (sparse) and K_b{a,c}, K_a{a,b,c} (dense: few rows/columns).
  const auto& K = impl_->K;
  std::vector<Eigen::Triplet<double>> tbb;
  Eigen::MatrixXd k_ba = Eigen::MatrixXd::Zero(b_.size(), a_.size()),
                  k_bc = Eigen::MatrixXd::Zero(b_.size(), c_.size());
  Eigen::MatrixXd k_aa = Eigen::MatrixXd::Zero(a_.size(), a_.size()),
                  k_ac = Eigen::MatrixXd::Zero(a_.size(), c_.size());
  Eigen::MatrixXd k_ab = Eigen::MatrixXd::Zero(a_.size(), b_.size());
  for (int col = 0; col < K.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, col); it; ++it) {
      const int r = int(it.row()), c = int(it.col());
      const int lr = local[r], lc = local[c];
      const DofRole rr = roles[r], rc = roles[c];
      if (rr == DofRole::kFree) {
        if (rc == DofRole::kFree)
          tbb.emplace_back(lr, lc, it.value());
        else if (rc == DofRole::kPrescribed)
          k_ba(lr, lc) = it.value();
        else
          k_bc(lr, lc) = it.value();
      } else if (rr == DofRole::kPrescribed) {
        if (rc == DofRole::kFree)
          k_ab(lr, lc) = it.value();
        else if (rc == DofRole::kPrescribed)
          k_aa(lr, lc) = it.value();
        else
          k_ac(lr, lc) = it.value();
      }
    }
  Eigen::SparseMatrix<double> kbb(b_.size(), b_.size());
  kbb.setFromTriplets(tbb.begin(), tbb.end());
  impl_->ldlt.compute(kbb);
  if (impl_->ldlt.info() != Eigen::Success)
    throw InputError("<mfs model>", "dof_roles", "K_bb is singular: free DOFs not held by coupled/prescribed ones");
  g_a_ = -impl_->ldlt.solve(k_ba);  // eq. 6: U_b = -K_bb^-1 K_ba U_a (- K_bb^-1 K_bc U_c)
  s_aa_ = k_aa + k_ab * g_a_;       // f_a = K_aa U_a + K_ab U_b + K_ac U_c
  if (coupled_moves) {
    g_c_ = -impl_->ldlt.solve(k_bc);
    s_ac_ = k_ac + k_ab * g_c_;
  } else {
    g_c_ = Eigen::MatrixXd::Zero(b_.size(), c_.size());
    s_ac_ = Eigen::MatrixXd::Zero(a_.size(), c_.size());
  }
  factor_s_ = secondsSince(t0);
}

Eigen::VectorXd MfsLocalModel::reactionForce(const Eigen::VectorXd& u_a, const Eigen::VectorXd& u_c) const {
  return s_aa_ * u_a + s_ac_ * u_c;
}

Eigen::VectorXd MfsLocalModel::freeDisplacement(const Eigen::VectorXd& u_a, const Eigen::VectorXd& u_c) const {
  return g_a_ * u_a + g_c_ * u_c;
}

double MfsLocalModel::energyNorm(const Eigen::VectorXd& u) const { return u.dot(impl_->K * u); }

std::shared_ptr<MfsLocalModel> mfsTipModel(const HemisphereCloudSpec& spec, const Material& material,
                                           bool coupled_moves) {
  HemisphereCloud c = hemisphereCloud(spec);
  c.cloud.singular[0] = 1;  // eq. 5: the tip node interpolates the prescribed displacement
  const int N = int(c.cloud.nodes.size());
  std::vector<DofRole> roles(std::size_t(3 * N), DofRole::kFree);
  const int outer = int(c.shell_r_m.size()) - 1;
  for (int k = 0; k < 3; ++k) roles[std::size_t(k)] = DofRole::kPrescribed;
  for (int i = 1; i < N; ++i)
    if (c.node_shell[std::size_t(i)] == outer)
      for (int k = 0; k < 3; ++k) roles[std::size_t(3 * i + k)] = DofRole::kCoupled;
  auto m = std::make_shared<MfsLocalModel>(c.cloud, material);
  m->setRoles(roles, coupled_moves);
  return m;
}

}  // namespace inc
