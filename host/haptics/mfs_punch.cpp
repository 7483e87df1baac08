// Flat rigid punch on the MFS local model: node roles, condensation, the tool force and the cost of a haptic tick.
#include "host/haptics/mfs_punch.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>

#include "model/input_error.h"

namespace inc {

double flatPunchForce(double radius_m, double youngs_modulus_pa, double poisson_ratio, double indentation_m) {
  return 2.0 * radius_m * youngs_modulus_pa * indentation_m / (1.0 - poisson_ratio * poisson_ratio);
}

MfsPunchResult mfsFlatPunch(const MfsPunchSpec& p, const Material& material) {
  const char* f = "<mfs punch>";
  if (!(p.radius_m > 0.0) || !std::isfinite(p.radius_m)) throw InputError(f, "radius_m", "must be > 0");
  if (p.contact_shells < 1 || p.contact_shells > 12) throw InputError(f, "contact_shells", "must be in [1, 12]");
  if (!(p.domain_over_radius >= 2.0) || p.domain_over_radius > 100.0)
    throw InputError(f, "domain_over_radius", "must be in [2, 100]");
  if (p.ticks < 16) throw InputError(f, "ticks", "must be >= 16");
  const double a = p.radius_m, delta = p.indentation_m > 0.0 ? p.indentation_m : 1e-3 * a;
  const auto t0 = std::chrono::steady_clock::now();
  HemisphereCloudSpec s;
  s.inner_spacing_m = a / (p.contact_shells + 0.5);  // the punch edge midway between two rings
  s.inner_shells = p.contact_shells + 2;             // two more constant-spacing shells beyond the edge
  s.radius_m = p.domain_over_radius * a;
  s.growth = p.growth;
  HemisphereCloud cc = hemisphereCloud(s);
  const int n = int(cc.cloud.nodes.size());
  std::vector<DofRole> roles(std::size_t(3 * n), DofRole::kFree);
  const int last_shell = int(cc.shell_r_m.size()) - 1;
  MfsPunchResult r;
  for (int i = 0; i < n; ++i) {
    if (cc.node_surface[i] && cc.node_shell[i] <= p.contact_shells) {
      cc.cloud.singular[i] = 1;                 // eq. 5: the approximation interpolates the punch face
      roles[3 * i + 2] = DofRole::kPrescribed;  // frictionless: only u_z prescribed
      ++r.contact_nodes;
    }
    if (cc.node_shell[i] == last_shell)
      for (int k = 0; k < 3; ++k) roles[3 * i + k] = DofRole::kCoupled;  // far field held
  }
  MfsLocalModel m(cc.cloud, material);
  m.setRoles(roles, /*coupled_moves=*/false);
  r.setup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.nodes = n;
  const Eigen::VectorXd ua = Eigen::VectorXd::Constant(Eigen::Index(m.prescribedDofs().size()), -delta);
  const Eigen::VectorXd uc = Eigen::VectorXd::Zero(Eigen::Index(m.coupledDofs().size()));
  r.force_n = -m.reactionForce(ua, uc).sum();  // pushed down: the tool applies a -z force on the tissue
  r.analytic_n = flatPunchForce(a, material.youngs_modulus_pa, material.poisson_ratio, delta);
  // A haptic tick is eq. 6's f_a = S_aa U_a + S_ac U_c; timed in batches of 8 (the clock costs ~20 ns).
  constexpr int kBatch = 8;
  std::vector<double> wall, cpu;
  double sink = 0.0;
  Eigen::VectorXd u = ua;
  auto cpuNow = [] {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;  // ms
  };
  for (int b = 0; b < p.ticks / kBatch; ++b) {
    const auto b0 = std::chrono::steady_clock::now();
    const double c0 = cpuNow();
    for (int k = 0; k < kBatch; ++k) {
      u[0] = -delta * (1.0 + 1e-6 * k);  // a tool that moves: the product cannot be hoisted
      sink += m.reactionForce(u, uc)[0];
    }
    cpu.push_back((cpuNow() - c0) / kBatch);
    wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - b0).count() / kBatch);
  }
  std::sort(wall.begin(), wall.end());
  std::sort(cpu.begin(), cpu.end());
  r.tick_ms = wall[wall.size() / 2];
  r.tick_cpu_ms = cpu[cpu.size() / 2];
  if (!std::isfinite(sink)) r.force_n = sink;  // keeps the timed products observable; never true for a valid model
  return r;
}

}  // namespace inc
