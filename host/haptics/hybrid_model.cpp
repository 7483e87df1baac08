// Hybrid MFS + BEM haptic model: the contact frame, the interface compliance (half-space + BEM), the global thread.
#include "host/haptics/hybrid_model.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "model/input_error.h"
#include "physics/boussinesq.h"

namespace inc {

namespace {
constexpr double kGuardRel = 1e-2;  // boussinesq guard for surface points above the tangent plane (concave organs)

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

HybridHapticModel::HybridHapticModel(BemModel& global, const HemisphereCloudSpec& local_spec, const Material& material)
    : global_(global), local_(mfsTipModel(local_spec, material)) {  // K_bb factorised once: the cloud moves with
                                                                    // the contact, its stiffness does not
  setUp();
}

HybridHapticModel::HybridHapticModel(BemModel& global, std::shared_ptr<const MfsLocalModel> local)
    : global_(global), local_(std::move(local)) {
  if (!local_) throw InputError("<hybrid model>", "local", "no local model");
  setUp();
}

void HybridHapticModel::setUp() {
  const char* f = "<hybrid model>";
  const auto& a = local_->prescribedDofs();
  if (a.empty() || local_->coupledDofs().empty()) throw InputError(f, "roles", "the local model's roles are not set");
  p_ = Eigen::MatrixXd::Zero(3, Eigen::Index(a.size()));
  for (std::size_t i = 0; i < a.size(); ++i) p_(a[i] % 3, Eigen::Index(i)) = 1.0;
  double radius = 0.0;
  for (const Vec3d& x : local_->cloud().nodes) radius = std::max(radius, norm(x));
  for (int d : local_->coupledDofs()) {
    const Vec3d x = local_->cloud().nodes[d / 3];
    // The half-space field is singular at the contact point: the interface must keep away from it.
    if (norm(x) < 0.25 * radius)
      throw InputError(f, "roles", "coupled DOFs must lie on the outer shell, away from the tool");
    coupled_x_.push_back(x);
    coupled_dir_.push_back(d % 3);
  }
  tip_tool_ = a.size() == 3 && a[0] == 0 && a[1] == 1 && a[2] == 2;
  c_ = Eigen::MatrixXd::Zero(Eigen::Index(coupled_x_.size()), 3);
  tool_op_ = Eigen::MatrixXd::Zero(3, Eigen::Index(a.size()));
  u_c_ = Eigen::VectorXd::Zero(Eigen::Index(coupled_x_.size()));
  surface_u_ = Eigen::VectorXd::Zero(3 * global_.elementCount());
  frame_[0] = {1, 0, 0};
  frame_[1] = {0, 1, 0};
  frame_[2] = {0, 0, 1};
  published_ = HybridCoupling{};
  coupling_.reset(published_);
}

void HybridHapticModel::touch(int element) {
  const char* f = "<hybrid model>";
  if (element < 0 || element >= global_.elementCount()) throw InputError(f, "element", "out of range");
  const auto t0 = std::chrono::steady_clock::now();
  global_.setContact({});  // the tool is a load on the organ, not a held patch: base conditions only
  const std::vector<BemBc> bc = global_.currentBc();
  if (bc[element] == BemBc::kDisplacement)
    throw InputError(f, "element", "is held by a displacement condition: the tool cannot press a clamped surface");
  contact_element_ = element;
  contact_point_ = global_.centroids()[element];
  contactFrame(global_.normals()[element], frame_);
  const double G = global_.shearModulus_pa(), nu = global_.poisson();
  const int E = global_.elementCount();

  // Regular part: for a unit force e_k at the contact, the BEM problem whose data are minus the
  // half-space field's tractions (traction elements) and displacements (held elements), averaged over each
  // element. The contact element lies in the half-space's surface plane, where that traction is zero.
  surface_b_ = Eigen::MatrixXd::Zero(3 * E, 3);
  surface_r_ = Eigen::MatrixXd::Zero(3 * E, 3);
  std::vector<Vec3d> pts;
  std::vector<double> wts;
  Eigen::MatrixXd known = Eigen::MatrixXd::Zero(3 * E, 3);
  for (int j = 0; j < E; ++j) {
    if (j == element) continue;
    const Vec3d cl = toLocal(global_.centroids()[j] - contact_point_);
    const Mat3d bc_centroid = boussinesqCerrutiDisplacement(cl, G, nu, kGuardRel);
    global_.elementQuadrature(j, contact_point_, pts, wts);
    const Vec3d nl = toLocal(global_.normals()[j]);
    double area = 0.0;
    Vec3d avg[3];
    for (std::size_t q = 0; q < pts.size(); ++q) {
      const Vec3d xl = toLocal(pts[q] - contact_point_);
      area += wts[q];
      if (bc[j] == BemBc::kTraction) {
        Mat3d sk[3];
        boussinesqCerrutiStresses(xl, G, nu, sk, 1e-4, kGuardRel);
        for (int k = 0; k < 3; ++k) {
          const Mat3d& s = sk[k];
          avg[k] +=
              Vec3d{s(0, 0) * nl.x + s(0, 1) * nl.y + s(0, 2) * nl.z, s(1, 0) * nl.x + s(1, 1) * nl.y + s(1, 2) * nl.z,
                    s(2, 0) * nl.x + s(2, 1) * nl.y + s(2, 2) * nl.z} *
              wts[q];
        }
      } else {
        const Mat3d b = boussinesqCerrutiDisplacement(xl, G, nu, kGuardRel);
        for (int k = 0; k < 3; ++k) avg[k] += Vec3d{b(k, 0), b(k, 1), b(k, 2)} * wts[q];
      }
    }
    for (int k = 0; k < 3; ++k) {
      const Vec3d v = toWorld(avg[k] * (-1.0 / area));
      known.block<3, 1>(3 * j, k) << v.x, v.y, v.z;
      const Vec3d ub = toWorld(Vec3d{bc_centroid(k, 0), bc_centroid(k, 1), bc_centroid(k, 2)});
      surface_b_.block<3, 1>(3 * j, k) << ub.x, ub.y, ub.z;
    }
  }
  const Eigen::MatrixXd y = global_.solve(known);  // the three load cases at once (one pass over the matrices)
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < E; ++j) {
      if (bc[j] == BemBc::kTraction)
        surface_r_.block<3, 1>(3 * j, k) = y.block<3, 1>(3 * j, k);
      else
        surface_r_.block<3, 1>(3 * j, k) = known.block<3, 1>(3 * j, k);
    }
    const Vec3d ur = toLocal(Vec3d{y(3 * element, k), y(3 * element + 1, k), y(3 * element + 2, k)});
    r_.col(k) << ur.x, ur.y, ur.z;
  }
  // Interface compliance: the half-space field at each coupled node plus the regular part, which varies on
  // the organ's scale and is taken uniform over the local region (a uniform part is a rigid translation of
  // the local model: it moves the field, not the force).
  for (std::size_t q = 0; q < coupled_x_.size(); ++q) {
    const Mat3d b = boussinesqCerrutiDisplacement(coupled_x_[q], G, nu);
    for (int k = 0; k < 3; ++k) c_(Eigen::Index(q), k) = b(k, coupled_dir_[q]) + r_(coupled_dir_[q], k);
  }
  // F = P f_a = P S_aa u_a + P S_ac C F  =>  F = (I - P S_ac C)^-1 P S_aa u_a.
  const Eigen::Matrix3d m = Eigen::Matrix3d::Identity() - p_ * local_->condensedAC() * c_;
  tool_op_ = m.partialPivLu().solve(p_ * local_->condensedAA());
  touching_ = true;
  published_.touching = true;
  published_.contact_point = contact_point_;
  for (int k = 0; k < 3; ++k) published_.frame[k] = frame_[k];
  published_.tip_stiffness = tip_tool_ ? Eigen::Matrix3d(tool_op_) : Eigen::Matrix3d::Zero();
  coupling_.write(published_);
  last_touch_s_ = secondsSince(t0);
}

void contactFrame(const Vec3d& n, Vec3d frame[3]) {
  const Vec3d helper = std::fabs(n.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
  frame[0] = cross(helper, n) * (1.0 / norm(cross(helper, n)));
  frame[1] = cross(n, frame[0]);
  frame[2] = n;
}

namespace {
// R K R^T with R's columns the frame's axes: a local-frame 3 x 3 operator in the world frame.
Eigen::Matrix3d toWorldFrame(const Eigen::Matrix3d& k, const Vec3d frame[3]) {
  Eigen::Matrix3d r;
  for (int a = 0; a < 3; ++a) r.col(a) << frame[a].x, frame[a].y, frame[a].z;
  return r * k * r.transpose();
}
}  // namespace

Eigen::Matrix3d HybridHapticModel::worldToolStiffness() const {
  if (!tip_tool_) throw InputError("<hybrid model>", "tool", "worldToolStiffness needs a tip tool");
  if (!touching_) return Eigen::Matrix3d::Zero();
  return toWorldFrame(Eigen::Matrix3d(tool_op_), frame_);
}

Eigen::MatrixXd HybridHapticModel::worldSurfaceCompliance() const {
  if (!touching_) return Eigen::MatrixXd::Zero(3 * global_.elementCount(), 3);
  Eigen::Matrix3d rt;  // R^T: a world force to the local frame
  for (int a = 0; a < 3; ++a) rt.row(a) << frame_[a].x, frame_[a].y, frame_[a].z;
  return (surface_b_ + surface_r_) * rt;
}

Eigen::Matrix3d HybridHapticModel::worldLocalOnlyStiffness(int element) const {
  if (!tip_tool_) throw InputError("<hybrid model>", "tool", "worldLocalOnlyStiffness needs a tip tool");
  if (element < 0 || element >= global_.elementCount()) throw InputError("<hybrid model>", "element", "out of range");
  Vec3d frame[3];
  contactFrame(global_.normals()[element], frame);
  return toWorldFrame(Eigen::Matrix3d(p_ * local_->condensedAA()), frame);
}

void HybridHapticModel::release() {
  touching_ = false;
  contact_element_ = -1;
  published_.touching = false;
  published_.tip_stiffness.setZero();
  coupling_.write(published_);
}

Eigen::Vector3d HybridHapticModel::toolForceLocal(const Eigen::VectorXd& u_a) const {
  if (u_a.size() != tool_op_.cols()) throw InputError("<hybrid model>", "u_a", "one value per prescribed DOF");
  if (!touching_) return Eigen::Vector3d::Zero();
  return tool_op_ * u_a;
}

Eigen::Vector3d HybridHapticModel::localOnlyForceLocal(const Eigen::VectorXd& u_a) const {
  if (u_a.size() != p_.cols()) throw InputError("<hybrid model>", "u_a", "one value per prescribed DOF");
  return p_ * (local_->condensedAA() * u_a);
}

Vec3d HybridHapticModel::localOnlyForce(const Vec3d& tip_displacement_world) const {
  if (!tip_tool_) throw InputError("<hybrid model>", "tool", "localOnlyForce(Vec3d) needs a tip tool");
  const Vec3d dl = toLocal(tip_displacement_world);
  const Eigen::Vector3d f = localOnlyForceLocal(Eigen::Vector3d(dl.x, dl.y, dl.z));
  return toWorld(Vec3d{-f[0], -f[1], -f[2]});
}

double HybridHapticModel::staggeredIterationFactor() const {
  const Eigen::Matrix3d m = p_ * local_->condensedAC() * c_;
  return m.eigenvalues().cwiseAbs().maxCoeff();
}

void HybridHapticModel::globalStep(const Vec3d& tip_displacement_world, double t_s) {
  if (!tip_tool_) throw InputError("<hybrid model>", "tool", "globalStep needs a tip tool");
  const auto t0 = std::chrono::steady_clock::now();
  if (touching_) {
    const Vec3d dl = toLocal(tip_displacement_world);
    const Eigen::Vector3d F = tool_op_ * Eigen::Vector3d(dl.x, dl.y, dl.z);  // on the organ, local frame
    u_c_ = c_ * F;                               // the local field's boundary (freeDisplacement for display)
    surface_u_ = (surface_b_ + surface_r_) * F;  // the organ's surface, world frame
    surface_u_.segment<3>(3 * contact_element_) << tip_displacement_world.x, tip_displacement_world.y,
        tip_displacement_world.z;  // the contact element follows the tool (the half-space field is singular there)
  } else {
    u_c_.setZero();
    surface_u_.setZero();
  }
  published_.time_s = t_s;
  published_.global_step = global_steps_.load() + 1;
  coupling_.write(published_);
  global_steps_.fetch_add(1);
  last_global_s_ = secondsSince(t0);
}

ForceResult HybridHapticModel::localTick(const Vec3d& d) {
  coupling_.update();
  const HybridCoupling& c = coupling_.front();
  ForceResult r;
  r.data_time_s = c.time_s;
  if (!c.touching) return r;
  const Eigen::Vector3d dl(dot(d, c.frame[0]), dot(d, c.frame[1]), dot(d, c.frame[2]));
  const Eigen::Vector3d F = c.tip_stiffness * dl;  // force the tool applies to the organ (local)
  r.force_n = (c.frame[0] * F[0] + c.frame[1] * F[1] + c.frame[2] * F[2]) * -1.0;  // the tissue pushes back
  return r;
}

GlobalLoop::GlobalLoop(HybridHapticModel& model, HapticLoop& haptic, double rate_hz, Vec3d rest_tip_position_m)
    : model_(model), haptic_(haptic), rest_(rest_tip_position_m) {
  if (!(rate_hz > 0.0 && rate_hz <= 1000.0)) throw InputError("<global loop>", "rate_hz", "must be in (0, 1000]");
  period_s_ = 1.0 / rate_hz;
}

GlobalLoop::~GlobalLoop() { stop(); }

void GlobalLoop::start() {
  stop_.store(false);
  periods_.clear();
  periods_.reserve(100000);
  work_.clear();
  work_.reserve(100000);
  thread_ = std::thread([this] {
    // Below normal priority (raising nice is always permitted): the global step can wait a few ms, the
    // haptic tick beside it cannot. Failure leaves the default priority, which is only less polite.
    (void)setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 5);
    using clk = std::chrono::steady_clock;
    auto next = clk::now();
    auto last = next;
    bool first = true;
    while (!stop_.load()) {
      std::this_thread::sleep_until(next);
      const auto now = clk::now();
      if (!first && periods_.size() < periods_.capacity())
        periods_.push_back(std::chrono::duration<double>(now - last).count());
      first = false;
      last = now;
      auto& st = haptic_.status();
      st.update();
      const HapticStatus& s = st.front();
      if (retouch_ && model_.contactElement() >= 0) model_.touch(model_.contactElement());
      model_.globalStep(s.sample.position_m - rest_, s.t_s);
      if (work_.size() < work_.capacity()) work_.push_back(std::chrono::duration<double>(clk::now() - now).count());
      next += std::chrono::duration_cast<clk::duration>(std::chrono::duration<double>(period_s_));
      if (clk::now() > next) next = clk::now();  // late: no burst of catch-up steps
    }
  });
}

void GlobalLoop::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

}  // namespace inc
