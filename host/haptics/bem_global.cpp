// Boundary-element global model: sphere meshes, Kelvin-kernel quadrature, assembly, inverse and SMW updates.
#include "host/haptics/bem_global.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include "host/compiled/material_checks.h"
#include "model/input_error.h"
#include "physics/kelvin.h"

namespace inc {

namespace {
double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Degree-5, 7-point rule on a triangle (barycentric coordinates, weights sum to 1).
struct TriRule {
  double b[7][3];
  double w[7];
};
const TriRule& triRule() {
  static const TriRule r = [] {
    TriRule t{};
    const double a1 = 0.059715871789770, b1 = 0.470142064105115, w1 = 0.132394152788506;
    const double a2 = 0.797426985353087, b2 = 0.101286507323456, w2 = 0.125939180544827;
    const double pts[7][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3},
                              {a1, b1, b1},
                              {b1, a1, b1},
                              {b1, b1, a1},
                              {a2, b2, b2},
                              {b2, a2, b2},
                              {b2, b2, a2}};
    const double ws[7] = {0.225, w1, w1, w1, w2, w2, w2};
    for (int i = 0; i < 7; ++i) {
      for (int k = 0; k < 3; ++k) t.b[i][k] = pts[i][k];
      t.w[i] = ws[i];
    }
    return t;
  }();
  return r;
}

// Gauss-Legendre on [0, 1] by Newton iteration on P_n.
void gaussLegendre01(int n, std::vector<double>& x, std::vector<double>& w) {
  x.resize(n);
  w.resize(n);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::fabs(dz) < 1e-15) break;
    }
    x[i] = 0.5 * (1.0 - z);
    w[i] = 1.0 / ((1.0 - z * z) * dp * dp);
  }
}

struct Blocks {
  Mat3d g, h;
};

// Regular integration of U* and T* over triangle (p0, p1, p2) for the source xi, subdivided 4^level.
void integrateRegular(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, const Vec3d& n, const Vec3d& xi, int level,
                      double mu, double nu, bool with_h, Blocks& out) {
  if (level > 0) {
    const Vec3d m01 = (p0 + p1) * 0.5, m12 = (p1 + p2) * 0.5, m20 = (p2 + p0) * 0.5;
    integrateRegular(p0, m01, m20, n, xi, level - 1, mu, nu, with_h, out);
    integrateRegular(m01, p1, m12, n, xi, level - 1, mu, nu, with_h, out);
    integrateRegular(m20, m12, p2, n, xi, level - 1, mu, nu, with_h, out);
    integrateRegular(m01, m12, m20, n, xi, level - 1, mu, nu, with_h, out);
    return;
  }
  const double area = 0.5 * norm(cross(p1 - p0, p2 - p0));
  const TriRule& r = triRule();
  for (int q = 0; q < 7; ++q) {
    const Vec3d x = p0 * r.b[q][0] + p1 * r.b[q][1] + p2 * r.b[q][2];
    const double w = r.w[q] * area;
    Mat3d u = kelvinDisplacement(x - xi, mu, nu);
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) out.g(k, l) += w * u(k, l);
    if (with_h) {
      Mat3d p = kelvinTraction(x - xi, n, nu);
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) out.h(k, l) += w * p(k, l);
    }
  }
}

int subdivisionLevel(double dist, double size) {
  if (dist > 4.0 * size) return 0;
  if (dist > 2.0 * size) return 1;
  if (dist > 1.0 * size) return 2;
  return 3;
}
}  // namespace

TriangleMesh icosphereMesh(double radius_m, int level) {
  if (!(radius_m > 0.0) || level < 0 || level > 6)
    throw InputError("<icosphere>", "level", "radius > 0, level in [0, 6]");
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriangleMesh m;
  m.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& v : m.vertices) v = v * (1.0 / norm(v));
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      Vec3d v = (m.vertices[a] + m.vertices[b]) * 0.5;
      m.vertices.push_back(v * (1.0 / norm(v)));
      const int id = int(m.vertices.size()) - 1;
      mid[key] = id;
      return id;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& f : m.triangles) {
      const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles.swap(next);
  }
  for (auto& v : m.vertices) v = v * radius_m;
  for (auto& f : m.triangles) {  // outward orientation
    const Vec3d n = cross(m.vertices[f[1]] - m.vertices[f[0]], m.vertices[f[2]] - m.vertices[f[0]]);
    if (dot(n, m.vertices[f[0]] + m.vertices[f[1]] + m.vertices[f[2]]) < 0.0) std::swap(f[1], f[2]);
  }
  return m;
}

TriangleMesh uvSphereMesh(double radius_m, int bands, int segments) {
  if (!(radius_m > 0.0) || bands < 2 || segments < 3)
    throw InputError("<uv sphere>", "bands", "bands >= 2, segments >= 3");
  TriangleMesh m;
  m.vertices.push_back({0, 0, radius_m});
  for (int b = 1; b < bands; ++b) {
    const double th = M_PI * b / bands;
    for (int s = 0; s < segments; ++s) {
      const double ph = 2.0 * M_PI * s / segments;
      m.vertices.push_back(
          {radius_m * std::sin(th) * std::cos(ph), radius_m * std::sin(th) * std::sin(ph), radius_m * std::cos(th)});
    }
  }
  m.vertices.push_back({0, 0, -radius_m});
  const int south = int(m.vertices.size()) - 1;
  auto ring = [&](int b, int s) { return 1 + (b - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) m.triangles.push_back({0, ring(1, s), ring(1, s + 1)});
  for (int b = 1; b + 1 < bands; ++b)
    for (int s = 0; s < segments; ++s) {
      m.triangles.push_back({ring(b, s), ring(b + 1, s), ring(b + 1, s + 1)});
      m.triangles.push_back({ring(b, s), ring(b + 1, s + 1), ring(b, s + 1)});
    }
  for (int s = 0; s < segments; ++s) m.triangles.push_back({south, ring(bands - 1, s + 1), ring(bands - 1, s)});
  for (auto& f : m.triangles) {
    const Vec3d n = cross(m.vertices[f[1]] - m.vertices[f[0]], m.vertices[f[2]] - m.vertices[f[0]]);
    if (dot(n, m.vertices[f[0]] + m.vertices[f[1]] + m.vertices[f[2]]) < 0.0) std::swap(f[1], f[2]);
  }
  return m;
}

BemModel::BemModel(const TriangleMesh& mesh, const Material& material, const Progress& progress) : mesh_(mesh) {
  const char* f = "<bem model>";
  validateMaterial(material, f);  // E and nu (the global model uses no density or damping)
  if (mesh.triangles.size() < 4) throw InputError(f, "mesh", "needs a closed mesh of at least 4 triangles");
  shear_pa_ = material.youngs_modulus_pa / (2.0 * (1.0 + material.poisson_ratio));
  nu_ = material.poisson_ratio;
  const auto t0 = std::chrono::steady_clock::now();
  const int E = int(mesh.triangles.size());
  for (int j = 0; j < E; ++j) {
    const auto& tri = mesh.triangles[j];
    for (int k = 0; k < 3; ++k)
      if (tri[k] < 0 || tri[k] >= int(mesh.vertices.size()))
        throw InputError(f, "triangle " + std::to_string(j), "vertex index out of range");
    const Vec3d a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]], c = mesh.vertices[tri[2]];
    const Vec3d n = cross(b - a, c - a);
    const double area2 = norm(n);
    if (!(area2 > 0.0)) throw InputError(f, "triangle " + std::to_string(j), "degenerate (zero area)");
    centroids_.push_back((a + b + c) * (1.0 / 3.0));
    normals_.push_back(n * (1.0 / area2));
    areas_.push_back(0.5 * area2);
  }
  H_ = Eigen::MatrixXd::Zero(3 * E, 3 * E);
  G_ = Eigen::MatrixXd::Zero(3 * E, 3 * E);
  std::vector<double> gx, gw;
  gaussLegendre01(8, gx, gw);
  for (int i = 0; i < E; ++i) {
    const Vec3d xi = centroids_[i];
    Mat3d hsum;
    for (int j = 0; j < E; ++j) {
      const auto& tri = mesh.triangles[j];
      const Vec3d a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]], c = mesh.vertices[tri[2]];
      Blocks blk;
      if (i != j) {
        const int level = subdivisionLevel(norm(centroids_[j] - xi), std::sqrt(2.0 * areas_[j]));
        integrateRegular(a, b, c, normals_[j], xi, level, shear_pa_, nu_, true, blk);
        hsum += blk.h;
      } else {
        // Weakly singular U*: three triangles with apex at the centroid, Duffy map x = xi + u (p - xi)
        // + u v (q - p) whose Jacobian u cancels the 1/r. T* on a flat element: H_ii from rigid motion.
        const Vec3d corners[3] = {a, b, c};
        for (int e = 0; e < 3; ++e) {
          const Vec3d p = corners[e], q = corners[(e + 1) % 3];
          const double area2 = norm(cross(p - xi, q - xi));
          for (int iu = 0; iu < 8; ++iu)
            for (int iv = 0; iv < 8; ++iv) {
              const double u = gx[iu], v = gx[iv];
              const Vec3d x = xi + (p - xi) * u + (q - p) * (u * v);
              const double w = gw[iu] * gw[iv] * u * area2;
              const Mat3d um = kelvinDisplacement(x - xi, shear_pa_, nu_);
              for (int k = 0; k < 3; ++k)
                for (int l = 0; l < 3; ++l) blk.g(k, l) += w * um(k, l);
            }
        }
      }
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) {
          G_(3 * i + k, 3 * j + l) = blk.g(k, l);
          if (i != j) H_(3 * i + k, 3 * j + l) = blk.h(k, l);
        }
    }
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) H_(3 * i + k, 3 * i + l) = -hsum(k, l);  // c + H^_ii: rigid translation
    if (progress && (i % 16 == 15 || i + 1 == E)) progress(double(i + 1) / E);
  }
  assembly_s_ = secondsSince(t0);
}

Eigen::VectorXd BemModel::solveTractionProblem(const Eigen::VectorXd& t) const {
  const int n = 3 * elementCount();
  if (t.size() != n) throw InputError("<bem model>", "traction", "need 3 values per element");
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(n, 6);
  for (int j = 0; j < elementCount(); ++j) {
    const Vec3d x = centroids_[j];
    for (int k = 0; k < 3; ++k) R(3 * j + k, k) = 1.0;
    for (int m = 0; m < 3; ++m) {
      Vec3d e;
      e[m] = 1.0;
      const Vec3d r = cross(e, x);
      for (int k = 0; k < 3; ++k) R(3 * j + k, 3 + m) = r[k];
    }
  }
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n + 6, n + 6);
  A.topLeftCorner(n, n) = H_;
  A.topRightCorner(n, 6) = R;
  A.bottomLeftCorner(6, n) = R.transpose();
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 6);
  b.head(n) = G_ * t;
  return A.partialPivLu().solve(b).head(n);
}

Eigen::MatrixXd BemModel::matrixFor(const std::vector<BemBc>& bc) const {
  Eigen::MatrixXd A(H_.rows(), H_.cols());
  for (int j = 0; j < elementCount(); ++j)
    A.middleCols(3 * j, 3) = bc[j] == BemBc::kTraction ? Eigen::MatrixXd(H_.middleCols(3 * j, 3))
                                                       : Eigen::MatrixXd(-G_.middleCols(3 * j, 3));
  return A;
}

Eigen::VectorXd BemModel::rhs(const Eigen::VectorXd& known, const std::vector<BemBc>& bc) const {
  if (known.size() != 3 * elementCount()) throw InputError("<bem model>", "known", "need 3 values per element");
  Eigen::VectorXd f = Eigen::VectorXd::Zero(known.size());
  for (int j = 0; j < elementCount(); ++j) {
    const Eigen::Vector3d v = known.segment<3>(3 * j);
    if (v.isZero(0.0)) continue;
    if (bc[j] == BemBc::kTraction)
      f += G_.middleCols(3 * j, 3) * v;
    else
      f -= H_.middleCols(3 * j, 3) * v;
  }
  return f;
}

namespace {
// out += sign * A X for a tall X of a few columns, column by column of A: each column of A is read from memory
// once and used for every column of X (a general matrix product would pack A first; for a few load cases the
// product is memory bound, and packing doubled the time). Zero rows of X are skipped.
void addSkinnyProduct(const Eigen::MatrixXd& A, const Eigen::MatrixXd& X, double sign, Eigen::MatrixXd& out) {
  for (Eigen::Index j = 0; j < A.cols(); ++j) {
    if (X.row(j).isZero(0.0)) continue;
    for (Eigen::Index k = 0; k < X.cols(); ++k) out.col(k) += (sign * X(j, k)) * A.col(j);
  }
}
}  // namespace

Eigen::MatrixXd BemModel::rhs(const Eigen::MatrixXd& known, const std::vector<BemBc>& bc) const {
  if (known.rows() != 3 * elementCount()) throw InputError("<bem model>", "known", "need 3 rows per element");
  // F = G t - H u: column 3j + l of G multiplies a known traction, of H a known displacement.
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(known.rows(), known.cols()), u = t;
  for (int j = 0; j < elementCount(); ++j)
    (bc[j] == BemBc::kTraction ? t : u).middleRows(3 * j, 3) = known.middleRows(3 * j, 3);
  Eigen::MatrixXd f = Eigen::MatrixXd::Zero(known.rows(), known.cols());
  addSkinnyProduct(G_, t, 1.0, f);
  addSkinnyProduct(H_, u, -1.0, f);
  return f;
}

void BemModel::factorBase(const std::vector<BemBc>& base, const Progress& progress) {
  if (int(base.size()) != elementCount()) throw InputError("<bem model>", "base", "need one condition per element");
  const auto t0 = std::chrono::steady_clock::now();
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(matrixFor(base));
  // A^-1 = LU^-1 I by blocks of columns (the solves are 3/4 of the work): a progress bar that moves.
  const Eigen::Index n = H_.rows(), block = 96;
  Eigen::MatrixXd inv(n, n);
  for (Eigen::Index c = 0; c < n; c += block) {
    const Eigen::Index w = std::min(block, n - c);
    inv.middleCols(c, w) = lu.solve(Eigen::MatrixXd::Identity(n, n).middleCols(c, w));
    if (progress) progress(double(c + w) / double(n));
  }
  setBaseInverse(base, std::move(inv));
  factor_s_ = secondsSince(t0);
}

void BemModel::setBaseInverse(const std::vector<BemBc>& base, Eigen::MatrixXd a_inv) {
  if (int(base.size()) != elementCount()) throw InputError("<bem model>", "base", "need one condition per element");
  if (a_inv.rows() != H_.rows() || a_inv.cols() != H_.cols())
    throw InputError("<bem model>", "inverse",
                     "must be " + std::to_string(H_.rows()) + " x " + std::to_string(H_.cols()));
  if (!a_inv.allFinite()) throw InputError("<bem model>", "base", "system is singular (no displacement support?)");
  base_ = base;
  a_inv_ = std::move(a_inv);
  contact_.clear();
  changed_cols_.clear();
  z_.resize(0, 0);
  factor_s_ = 0.0;
}

std::vector<BemBc> BemModel::currentBc() const {
  std::vector<BemBc> bc = base_;
  for (int j : contact_) bc[j] = BemBc::kDisplacement;
  return bc;
}

void BemModel::setContact(const std::vector<int>& contact_elements) {
  if (a_inv_.size() == 0) throw InputError("<bem model>", "contact", "factorBase() first");
  contact_.clear();
  changed_cols_.clear();
  for (int j : contact_elements) {
    if (j < 0 || j >= elementCount()) throw InputError("<bem model>", "contact", "element index out of range");
    if (base_[j] == BemBc::kDisplacement) continue;  // already held in the base
    if (std::find(contact_.begin(), contact_.end(), j) != contact_.end()) continue;
    contact_.push_back(j);
    for (int k = 0; k < 3; ++k) changed_cols_.push_back(3 * j + k);
  }
  const int k = int(changed_cols_.size());
  if (k == 0) {
    z_.resize(0, 0);
    return;
  }
  // D: new minus old columns (-G_j - H_j); A' = A + D S^T; A'^-1 = A^-1 - Z (I + S^T Z)^-1 S^T A^-1.
  Eigen::MatrixXd D(H_.rows(), k);
  for (int c = 0; c < k; ++c) D.col(c) = -G_.col(changed_cols_[c]) - H_.col(changed_cols_[c]);
  z_ = a_inv_ * D;
  Eigen::MatrixXd C = Eigen::MatrixXd::Identity(k, k);
  for (int r = 0; r < k; ++r) C.row(r) += z_.row(changed_cols_[r]);
  c_lu_.compute(C);
}

Eigen::VectorXd BemModel::solve(const Eigen::VectorXd& known) const {
  const Eigen::VectorXd y0 = a_inv_ * rhs(known, currentBc());
  if (changed_cols_.empty()) return y0;
  Eigen::VectorXd ys(changed_cols_.size());
  for (std::size_t r = 0; r < changed_cols_.size(); ++r) ys[r] = y0[changed_cols_[r]];
  return y0 - z_ * c_lu_.solve(ys);
}

Eigen::MatrixXd BemModel::solve(const Eigen::MatrixXd& known) const {
  Eigen::MatrixXd y0 = Eigen::MatrixXd::Zero(known.rows(), known.cols());
  addSkinnyProduct(a_inv_, rhs(known, currentBc()), 1.0, y0);
  if (changed_cols_.empty()) return y0;
  Eigen::MatrixXd ys(changed_cols_.size(), known.cols());
  for (std::size_t r = 0; r < changed_cols_.size(); ++r) ys.row(Eigen::Index(r)) = y0.row(changed_cols_[r]);
  return y0 - z_ * c_lu_.solve(ys);
}

Eigen::VectorXd BemModel::solveFresh(const Eigen::VectorXd& known) const {
  const auto bc = currentBc();
  return matrixFor(bc).partialPivLu().solve(rhs(known, bc));
}

void BemModel::interiorRows(const Vec3d& xi, Eigen::MatrixXd& g_rows, Eigen::MatrixXd& h_rows) const {
  const int E = elementCount();
  g_rows.setZero(3, 3 * E);
  h_rows.setZero(3, 3 * E);
  for (int j = 0; j < E; ++j) {
    const auto& tri = mesh_.triangles[j];
    Blocks blk;
    const int level = subdivisionLevel(norm(centroids_[j] - xi), std::sqrt(2.0 * areas_[j]));
    integrateRegular(mesh_.vertices[tri[0]], mesh_.vertices[tri[1]], mesh_.vertices[tri[2]], normals_[j], xi, level,
                     shear_pa_, nu_, true, blk);
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) {
        g_rows(k, 3 * j + l) = blk.g(k, l);
        h_rows(k, 3 * j + l) = blk.h(k, l);
      }
  }
}

namespace {
void subdividedRule(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, int level, std::vector<Vec3d>& pts,
                    std::vector<double>& wts) {
  if (level > 0) {
    const Vec3d m01 = (p0 + p1) * 0.5, m12 = (p1 + p2) * 0.5, m20 = (p2 + p0) * 0.5;
    subdividedRule(p0, m01, m20, level - 1, pts, wts);
    subdividedRule(m01, p1, m12, level - 1, pts, wts);
    subdividedRule(m20, m12, p2, level - 1, pts, wts);
    subdividedRule(m01, m12, m20, level - 1, pts, wts);
    return;
  }
  const double area = 0.5 * norm(cross(p1 - p0, p2 - p0));
  const TriRule& r = triRule();
  for (int q = 0; q < 7; ++q) {
    pts.push_back(p0 * r.b[q][0] + p1 * r.b[q][1] + p2 * r.b[q][2]);
    wts.push_back(r.w[q] * area);
  }
}
}  // namespace

void BemModel::elementQuadrature(int j, const Vec3d& near_point, std::vector<Vec3d>& points,
                                 std::vector<double>& weights) const {
  if (j < 0 || j >= elementCount()) throw InputError("<bem model>", "element", "out of range");
  points.clear();
  weights.clear();
  const auto& tri = mesh_.triangles[j];
  const int level = subdivisionLevel(norm(centroids_[j] - near_point), std::sqrt(2.0 * areas_[j]));
  subdividedRule(mesh_.vertices[tri[0]], mesh_.vertices[tri[1]], mesh_.vertices[tri[2]], level, points, weights);
}

Vec3d BemModel::interiorDisplacement(const Vec3d& xi, const Eigen::VectorXd& u, const Eigen::VectorXd& t) const {
  Vec3d out;
  for (int j = 0; j < elementCount(); ++j) {
    const auto& tri = mesh_.triangles[j];
    Blocks blk;
    const int level = subdivisionLevel(norm(centroids_[j] - xi), std::sqrt(2.0 * areas_[j]));
    integrateRegular(mesh_.vertices[tri[0]], mesh_.vertices[tri[1]], mesh_.vertices[tri[2]], normals_[j], xi, level,
                     shear_pa_, nu_, true, blk);
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) out[k] += blk.g(k, l) * t[3 * j + l] - blk.h(k, l) * u[3 * j + l];
  }
  return out;
}

}  // namespace inc
