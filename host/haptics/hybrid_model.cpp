// Hybrid MFS + BEM haptic model: frames, coupling through the Somigliana identity, the global thread.
#include "host/haptics/hybrid_model.h"

#include <chrono>
#include <cmath>

#include "host/input_error.h"

namespace inc {

HybridHapticModel::HybridHapticModel(BemModel& global, const HemisphereCloudSpec& local_spec,
                                     const MfsMaterial& material, double contact_radius_m)
    : global_(global), cloud_(hemisphereCloud(local_spec)), contact_radius_m_(contact_radius_m) {
  if (!(contact_radius_m > 0.0) || !std::isfinite(contact_radius_m))
    throw InputError("<hybrid model>", "contact_radius_m", "must be > 0");
  cloud_.cloud.singular[0] = 1;  // the tool-tip node, eq. 5
  const int N = int(cloud_.cloud.nodes.size());
  std::vector<DofRole> roles(3 * N, DofRole::kFree);
  const int outer = int(cloud_.shell_r_m.size()) - 1;
  for (int k = 0; k < 3; ++k) roles[k] = DofRole::kPrescribed;
  for (int i = 1; i < N; ++i)
    if (cloud_.node_shell[i] == outer) {
      for (int k = 0; k < 3; ++k) roles[3 * i + k] = DofRole::kCoupled;
      coupled_nodes_.push_back(i);
    }
  local_ = std::make_unique<MfsLocalModel>(cloud_.cloud, material);
  local_->setRoles(roles);  // factorised once: the local cloud moves with the contact, K_bb does not change
  CouplingData zero;
  zero.u_c = Eigen::VectorXd::Zero(3 * coupled_nodes_.size());
  coupling_.reset(zero);
}

Vec3d HybridHapticModel::toLocal(const Vec3d& w) const { return {dot(w, frame_[0]), dot(w, frame_[1]), dot(w, frame_[2])}; }
Vec3d HybridHapticModel::toWorld(const Vec3d& l) const { return frame_[0] * l.x + frame_[1] * l.y + frame_[2] * l.z; }

void HybridHapticModel::touch(int element) {
  if (element < 0 || element >= global_.elementCount()) throw InputError("<hybrid model>", "element", "out of range");
  contact_point_ = global_.centroids()[element];
  const Vec3d n = global_.normals()[element];
  const Vec3d helper = std::fabs(n.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
  frame_[0] = cross(helper, n) * (1.0 / norm(cross(helper, n)));
  frame_[1] = cross(n, frame_[0]);
  frame_[2] = n;
  contact_elements_.clear();
  for (int j = 0; j < global_.elementCount(); ++j)
    if (j == element || norm(global_.centroids()[j] - contact_point_) <= contact_radius_m_) contact_elements_.push_back(j);
  global_.setContact(contact_elements_);  // SMW: rank 3k update of the precomputed inverse
  const int nc = int(coupled_nodes_.size()), E = global_.elementCount();
  infl_g_.resize(3 * nc, 3 * E);
  infl_h_.resize(3 * nc, 3 * E);
  const double inset = 0.25 * (cloud_.shell_r_m.back() - cloud_.shell_r_m[cloud_.shell_r_m.size() - 2]);
  Eigen::MatrixXd g, h;
  for (int q = 0; q < nc; ++q) {
    // Surface-ring nodes lie on the tangent plane; evaluate a little inside, where Somigliana's c = 1.
    const Vec3d xw = contact_point_ + toWorld(cloud_.cloud.nodes[coupled_nodes_[q]]) - frame_[2] * inset;
    global_.interiorRows(xw, g, h);
    infl_g_.middleRows(3 * q, 3) = g;
    infl_h_.middleRows(3 * q, 3) = h;
  }
  CouplingData& c = coupling_.back();
  c.u_c.setZero();
  c.time_s = -1.0;
  coupling_.publish();
}

void HybridHapticModel::globalStep(const Vec3d& tip_displacement_world, double t_s) {
  const auto t0 = std::chrono::steady_clock::now();
  const int E = global_.elementCount();
  Eigen::VectorXd known = Eigen::VectorXd::Zero(3 * E);
  const auto bc = global_.currentBc();
  for (int j : contact_elements_) known.segment<3>(3 * j) << tip_displacement_world.x, tip_displacement_world.y,
        tip_displacement_world.z;
  const Eigen::VectorXd y = global_.solve(known);
  Eigen::VectorXd u(3 * E), t(3 * E);
  for (int j = 0; j < E; ++j) {
    if (bc[j] == BemBc::kTraction) {
      u.segment<3>(3 * j) = y.segment<3>(3 * j);
      t.segment<3>(3 * j) = known.segment<3>(3 * j);
    } else {
      u.segment<3>(3 * j) = known.segment<3>(3 * j);
      t.segment<3>(3 * j) = y.segment<3>(3 * j);
    }
  }
  CouplingData& c = coupling_.back();
  const Eigen::VectorXd uw = infl_g_ * t - infl_h_ * u;  // world frame, 3 per coupled node
  c.u_c.resize(uw.size());
  for (Eigen::Index q = 0; q < uw.size() / 3; ++q) {
    const Vec3d ul = toLocal(Vec3d{uw[3 * q], uw[3 * q + 1], uw[3 * q + 2]});
    c.u_c.segment<3>(3 * q) << ul.x, ul.y, ul.z;
  }
  c.time_s = t_s;
  c.global_step = global_steps_.load() + 1;
  coupling_.publish();
  global_steps_.fetch_add(1);
  last_global_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

ForceResult HybridHapticModel::localTick(const Vec3d& tip_displacement_world) {
  coupling_.update();
  const CouplingData& c = coupling_.front();
  const Vec3d dl = toLocal(tip_displacement_world);
  const Eigen::Vector3d ua(dl.x, dl.y, dl.z);
  const Eigen::VectorXd f = local_->reactionForce(ua, c.u_c);  // eq. 6 with the global boundary
  ForceResult r;
  r.force_n = toWorld(Vec3d{-f[0], -f[1], -f[2]});  // the tissue pushes back on the hand
  r.data_time_s = c.time_s;
  return r;
}

Vec3d HybridHapticModel::localOnlyForce(const Vec3d& tip_displacement_world) const {
  const Vec3d dl = toLocal(tip_displacement_world);
  const Eigen::VectorXd f =
      local_->reactionForce(Eigen::Vector3d(dl.x, dl.y, dl.z), Eigen::VectorXd::Zero(3 * coupled_nodes_.size()));
  return toWorld(Vec3d{-f[0], -f[1], -f[2]});
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
  thread_ = std::thread([this] {
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
      model_.globalStep(s.sample.position_m - rest_, s.t_s);
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
