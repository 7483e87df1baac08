// Haptics benchmark: 1 kHz loop period under load, MFS tick time vs nodes, BEM precompute and SMW update vs size.
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "host/haptics/bem_global.h"
#include "host/haptics/hybrid_model.h"
#include "host/haptics/mfs_local.h"

using namespace inc;
using clk = std::chrono::steady_clock;

namespace {
struct Csv {
  std::FILE* f = nullptr;
  void row(const std::string& section, const std::string& name, double param, double value, const std::string& unit) {
    if (f) std::fprintf(f, "%s,%s,%g,%.9g,%s\n", section.c_str(), name.c_str(), param, value, unit.c_str());
  }
};

double seconds(clk::time_point t0) { return std::chrono::duration<double>(clk::now() - t0).count(); }

double pct(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, std::size_t(q * double(v.size())))];
}

double threadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// Median CPU time of this thread (what the work costs, whatever else the shared machine runs).
template <typename F>
double medianCpuSeconds(int reps, F&& f) {
  f();  // warm-up
  std::vector<double> t;
  for (int i = 0; i < reps; ++i) {
    const double t0 = threadCpuSeconds();
    f();
    t.push_back(threadCpuSeconds() - t0);
  }
  return pct(t, 0.5);
}

template <typename F>
double medianSeconds(int reps, F&& f) {
  f();  // warm-up
  std::vector<double> t;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = clk::now();
    f();
    t.push_back(seconds(t0));
  }
  return pct(t, 0.5);
}

Trajectory pressPath(const Vec3d& rest, const Vec3d& n, double duration_s) {
  Trajectory tr;
  for (int i = 0; i <= 20; ++i) {
    DeviceSample s;
    s.t_s = duration_s * i / 20;
    s.position_m = rest - n * (1.5e-3 * std::sin(M_PI * i / 20));  // press in and release
    tr.samples.push_back(s);
  }
  return tr;
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Incision haptics benchmark (CPU): haptic loop, MFS local model, BEM global model"};
  std::string csv_path;
  bool quick = false;
  double loop_seconds = 5.0;
  app.add_option("--csv", csv_path, "write figures as CSV (section,name,param,value,unit)");
  app.add_flag("--quick", quick, "short run");
  app.add_option("--loop-seconds", loop_seconds, "duration of each haptic loop run");
  int threads = 1;
  app.add_option("--threads", threads, "Eigen threads (1: the haptic and global loops each own one core)");
  bool loop_only = false, no_realtime = false;
  int loop_runs = 1;
  app.add_flag("--loop-only", loop_only, "only the haptic loop runs (skip the BEM and MFS sections)");
  app.add_option("--loop-runs", loop_runs, "repeat each haptic loop run this many times (report the spread)");
  app.add_flag("--no-realtime", no_realtime, "do not ask for SCHED_FIFO (measure the fallback)");
  double spin_margin_us = -1.0;
  app.add_option("--spin-margin-us", spin_margin_us, "spin margin of the loop's wait (default: the loop's own)");
  CLI11_PARSE(app, argc, argv);
  Eigen::setNbThreads(std::max(1, threads));
  if (quick) loop_seconds = std::min(loop_seconds, 1.0);
  Csv csv;
  if (!csv_path.empty()) {
    csv.f = std::fopen(csv_path.c_str(), "w");
    if (!csv.f) {
      std::fprintf(stderr, "cannot write %s\n", csv_path.c_str());
      return 2;
    }
    std::fprintf(csv.f, "section,name,param,value,unit\n");
  }
  const int reps = quick ? 3 : 9;
  const bool realtime = !no_realtime;
  loop_runs = std::max(1, loop_runs);

  // --- BEM: precompute and SMW update against element count ---
  std::printf("BEM global model (Kelvin, constant triangles), E = 3 kPa, nu = 0.45\n");
  std::printf("%8s %6s %12s %12s %12s %12s\n", "elements", "dofs", "assemble_s", "inverse_s", "solve_ms", "fresh_ms");
  struct Mesh {
    std::string name;
    TriangleMesh mesh;
  };
  std::vector<Mesh> meshes = {
      {"ico80", icosphereMesh(0.04, 1)}, {"ico320", icosphereMesh(0.04, 2)}, {"kidney690", uvSphereMesh(0.04, 16, 23)}};
  if (!quick) meshes.push_back({"ico1280", icosphereMesh(0.04, 3)});
  double kidney_global_ms = 0.0, kidney_local_us = 0.0, kidney_touch_ms = 0.0;
  if (loop_only) meshes.clear();
  for (auto& m : meshes) {
    const auto t0 = clk::now();
    BemModel bem(m.mesh, {3e3, 0.45});
    const double assemble = seconds(t0);
    const int E = bem.elementCount();
    std::vector<BemBc> base(E, BemBc::kTraction);
    int top = 0;
    for (int j = 0; j < E; ++j) {
      if (bem.centroids()[j].z < -0.03) base[j] = BemBc::kDisplacement;
      if (bem.centroids()[j].z > bem.centroids()[top].z) top = j;
    }
    const auto t1 = clk::now();
    bem.factorBase(base);
    const double inv = seconds(t1);
    std::vector<int> byDist(E);
    for (int j = 0; j < E; ++j) byDist[j] = j;
    std::sort(byDist.begin(), byDist.end(), [&](int a, int b) {
      return norm(bem.centroids()[a] - bem.centroids()[top]) < norm(bem.centroids()[b] - bem.centroids()[top]);
    });
    bem.setContact({top});
    Eigen::VectorXd known = Eigen::VectorXd::Zero(3 * E);
    known[3 * top + 2] = -1e-3;
    const double solve = medianSeconds(reps, [&] { (void)bem.solve(known); });
    const double fresh = medianSeconds(quick ? 1 : 3, [&] { (void)bem.solveFresh(known); });
    std::printf("%8d %6d %12.3f %12.3f %12.3f %12.3f\n", E, 3 * E, assemble, inv, 1e3 * solve, 1e3 * fresh);
    csv.row("bem", m.name + "_assemble", E, assemble, "s");
    csv.row("bem", m.name + "_inverse", E, inv, "s");
    csv.row("bem", m.name + "_smw_solve", E, solve, "s");
    csv.row("bem", m.name + "_fresh_solve", E, fresh, "s");
    std::printf("   SMW contact update (rank 3k): ");
    for (int k : {1, 2, 4, 8, 16}) {
      if (k > E / 4) break;
      std::vector<int> contact(byDist.begin(), byDist.begin() + k);
      const double upd = medianSeconds(reps, [&] { bem.setContact(contact); });
      std::printf("rank %d %.3f ms  ", 3 * k, 1e3 * upd);
      csv.row("bem", m.name + "_smw_update", 3 * k, upd, "s");
    }
    std::printf("\n");
    if (m.name == "kidney690") {
      // The paper's kidney case: 688 polygons, 2068 DOFs, 40 Hz visual, 1 kHz haptic.
      bem.setContact({});
      HybridHapticModel hybrid(bem,
                               [] {
                                 HemisphereCloudSpec s;
                                 s.inner_spacing_m = 2e-3;
                                 s.inner_shells = 2;
                                 s.radius_m = 8e-3;
                                 return s;
                               }(),
                               {3e3, 0.45});
      kidney_touch_ms = 1e3 * medianSeconds(reps, [&] { hybrid.touch(top); });
      const double touch_cpu_ms = 1e3 * medianCpuSeconds(reps, [&] { hybrid.touch(top); });
      const Vec3d d = bem.normals()[top] * -1e-3;
      kidney_global_ms = 1e3 * medianSeconds(reps, [&] { hybrid.globalStep(d, 0.0); });
      kidney_local_us = 1e6 * medianSeconds(reps * 1000, [&] { (void)hybrid.localTick(d); });
      std::printf(
          "   kidney hybrid: contact change (touch: half-space data + 3 BEM solves) %.2f ms wall (%.2f ms CPU), "
          "global step %.3f ms "
          "(budget 25 ms at 40 Hz, margin %.0fx even with a new contact every frame: %.1fx), local tick %.3f us "
          "(budget 1000 us, margin %.0fx)\n",
          kidney_touch_ms, touch_cpu_ms, kidney_global_ms, 25.0 / kidney_global_ms,
          25.0 / (kidney_global_ms + kidney_touch_ms), kidney_local_us, 1000.0 / kidney_local_us);
      csv.row("kidney", "touch", E, kidney_touch_ms * 1e-3, "s");
      csv.row("kidney", "touch_cpu", E, touch_cpu_ms * 1e-3, "s");
      csv.row("kidney", "global_step", E, kidney_global_ms * 1e-3, "s");
      csv.row("kidney", "local_tick", E, kidney_local_us * 1e-6, "s");
    }
  }

  // --- MFS: per-tick time and factorisation against node count ---
  std::printf("\nMFS local model (tip node prescribed, outer shell coupled)\n");
  std::printf("%6s %6s %12s %12s %10s %10s %10s %12s\n", "nodes", "dofs", "assemble_ms", "factor_ms", "tick_p50_us",
              "tick_p99_us", "tick_max_us", "full_tick_us");
  std::vector<HemisphereCloudSpec> specs;
  for (int shells : {1, 2, 3, 4}) {
    HemisphereCloudSpec s;
    s.inner_spacing_m = 1.5e-3;
    s.inner_shells = shells;
    s.radius_m = 1.5e-3 * (shells + 1) * 1.6;
    specs.push_back(s);
    if (quick && shells == 3) break;
  }
  if (loop_only) specs.clear();
  for (const auto& spec : specs) {
    HemisphereCloud cc = hemisphereCloud(spec);
    cc.cloud.singular[0] = 1;
    const int N = int(cc.cloud.nodes.size());
    std::vector<DofRole> roles(3 * N, DofRole::kFree);
    for (int k = 0; k < 3; ++k) roles[k] = DofRole::kPrescribed;
    for (int i = 0; i < N; ++i)
      if (cc.node_shell[i] == int(cc.shell_r_m.size()) - 1)
        for (int k = 0; k < 3; ++k) roles[3 * i + k] = DofRole::kCoupled;
    MfsLocalModel m(cc.cloud, {3e3, 0.45});
    m.setRoles(roles);
    const Eigen::Vector3d ua(0.0, 2e-4, -1e-3);
    const Eigen::VectorXd uc = Eigen::VectorXd::Constant(m.coupledDofs().size(), 1e-5);
    std::vector<double> ticks, full;
    const int n = quick ? 2000 : 20000;
    Eigen::VectorXd f(3), ub;
    for (int i = 0; i < n; ++i) {
      const auto t0 = clk::now();
      f = m.reactionForce(ua, uc);
      ticks.push_back(seconds(t0));
      const auto t1 = clk::now();
      ub = m.freeDisplacement(ua, uc);  // the whole local field as well (display)
      full.push_back(seconds(t1) + ticks.back());
    }
    std::printf("%6d %6d %12.2f %12.2f %10.2f %10.2f %10.2f %12.2f\n", N, 3 * N, 1e3 * m.assemblySeconds(),
                1e3 * m.factorSeconds(), 1e6 * pct(ticks, 0.5), 1e6 * pct(ticks, 0.99),
                1e6 * *std::max_element(ticks.begin(), ticks.end()), 1e6 * pct(full, 0.5));
    csv.row("mfs", "assemble", N, m.assemblySeconds(), "s");
    csv.row("mfs", "factor", N, m.factorSeconds(), "s");
    csv.row("mfs", "tick_p50", N, pct(ticks, 0.5), "s");
    csv.row("mfs", "tick_p99", N, pct(ticks, 0.99), "s");
    csv.row("mfs", "tick_max", N, *std::max_element(ticks.begin(), ticks.end()), "s");
    csv.row("mfs", "tick_with_field_p50", N, pct(full, 0.5), "s");
  }

  // --- Haptic loop period: alone, beside the 40 Hz global loop, beside a global loop re-touching every step ---
  std::printf("\nHaptic loop at 1 kHz (%.1f s per run, %d run(s) each)\n", loop_seconds, loop_runs);
  std::printf("%-26s %8s %9s %9s %9s %8s %8s %11s %11s\n", "run", "ticks", "p50_ms", "p99_ms", "max_ms", "missed",
              "skipped", "compute_p99", "compute_max");
  double p99_loaded = 0.0;
  BemModel loop_bem(uvSphereMesh(0.04, 16, 23), {3e3, 0.45});
  std::vector<BemBc> loop_base(loop_bem.elementCount(), BemBc::kTraction);
  int loop_top = 0;
  for (int j = 0; j < loop_bem.elementCount(); ++j) {
    if (loop_bem.centroids()[j].z < -0.03) loop_base[j] = BemBc::kDisplacement;
    if (loop_bem.centroids()[j].z > loop_bem.centroids()[loop_top].z) loop_top = j;
  }
  loop_bem.factorBase(loop_base);
  const char* names[3] = {"hybrid local only", "hybrid+global@40Hz", "hybrid+global retouching"};
  std::string scheduling;
  for (int mode = 0; mode < 3; ++mode) {
    std::vector<double> p99s;
    for (int run = 0; run < loop_runs; ++run) {
      HemisphereCloudSpec spec;
      spec.inner_spacing_m = 2e-3;
      spec.inner_shells = 2;
      spec.radius_m = 8e-3;
      HybridHapticModel hybrid(loop_bem, spec, {3e3, 0.45});
      hybrid.touch(loop_top);
      const Vec3d rest = hybrid.contactPoint(), n = loop_bem.normals()[loop_top];
      ScriptedDevice dev(pressPath(rest, n, loop_seconds), ScriptedDevice::Mode::kByTime, 3.3);
      HapticLoopConfig cfg;
      cfg.realtime = realtime;
      if (spin_margin_us >= 0.0) cfg.spin_margin_s = cfg.realtime_spin_margin_s = 1e-6 * spin_margin_us;
      cfg.record_capacity = std::size_t(loop_seconds * 1000.0 * 1.2) + 1000;
      HapticLoop loop(
          dev, [&](const ForceRequest& q) { return hybrid.localTick(q.sample.position_m - rest); }, cfg);
      GlobalLoop global(hybrid, loop, 40.0, rest);
      global.setRetouchEachStep(mode == 2);
      loop.start();
      scheduling = loop.scheduling().message;
      if (mode > 0) global.start();
      std::this_thread::sleep_for(std::chrono::duration<double>(loop_seconds));
      global.stop();
      loop.stop();
      const PeriodStats s = loop.stats();
      std::printf("%-26s %8llu %9.4f %9.4f %9.4f %8llu %8llu %8.2f us %8.2f us\n", names[mode],
                  (unsigned long long)s.ticks, 1e3 * s.p50_s, 1e3 * s.p99_s, 1e3 * s.max_s,
                  (unsigned long long)s.missed, (unsigned long long)s.skipped, 1e6 * s.compute_p99_s,
                  1e6 * s.compute_max_s);
      if (mode > 0) {
        const auto gp = global.periods(), gw = global.workSeconds();
        std::printf("   global loop: %zu steps, period p50 %.2f ms p99 %.2f ms, work p50 %.3f ms max %.3f ms\n",
                    gp.size(), 1e3 * pct(gp, 0.5), 1e3 * pct(gp, 0.99), 1e3 * pct(gw, 0.5),
                    gw.empty() ? 0.0 : 1e3 * *std::max_element(gw.begin(), gw.end()));
        csv.row("loop", std::string(mode == 1 ? "global" : "retouch") + "_period_p50", 40, pct(gp, 0.5), "s");
        csv.row("loop", std::string(mode == 1 ? "global" : "retouch") + "_work_p50", 40, pct(gw, 0.5), "s");
      }
      const std::string tag = mode == 0 ? "idle" : (mode == 1 ? "loaded" : "retouch");
      csv.row("loop", tag + "_p50", 1000, s.p50_s, "s");
      csv.row("loop", tag + "_p99", 1000, s.p99_s, "s");
      csv.row("loop", tag + "_max", 1000, s.max_s, "s");
      csv.row("loop", tag + "_missed", 1000, double(s.missed), "ticks");
      csv.row("loop", tag + "_compute_p99", 1000, s.compute_p99_s, "s");
      p99s.push_back(s.p99_s);
    }
    if (loop_runs > 1)
      std::printf("   %s: p99 over %d runs: min %.4f ms, max %.4f ms\n", names[mode], loop_runs,
                  1e3 * *std::min_element(p99s.begin(), p99s.end()), 1e3 * *std::max_element(p99s.begin(), p99s.end()));
    if (mode == 1) p99_loaded = *std::max_element(p99s.begin(), p99s.end());
  }
  std::printf("haptic thread scheduling: %s\n", scheduling.c_str());
  if (csv.f) std::fclose(csv.f);
  std::printf(
      "SUMMARY bench_haptics: loop p99 %.3f ms beside the 40 Hz global loop; kidney contact change %.2f ms + "
      "global step %.3f ms (40 Hz margin %.1fx with a new contact every frame), local tick %.3f us (1 kHz "
      "margin %.0fx)\n",
      1e3 * p99_loaded, kidney_touch_ms, kidney_global_ms, 25.0 / (kidney_touch_ms + kidney_global_ms), kidney_local_us,
      1000.0 / kidney_local_us);
  return 0;
}
