// Frame time before, during and after tearing ~200 / ~4000 particles out of a leg-like skin (traditional vs Tresca, CPU
// and CUDA tearing step).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "host/tear/tearing_driver.h"
#include "model/backend.h"
#include "model/input_error.h"
#include "model/tearing_sheet.h"
#if INCISION_HAVE_CUDA
#include "kernels/device_info.h"
#endif

using namespace inc;

namespace {

struct Row {
  std::string backend, method;
  std::int64_t particles = 0, target = 0, gripped = 0, splits = 0, particles_after = 0;
  double ms_before = 0, ms_during = 0, ms_after = 0, ms_during_max = 0;
  double ms_tear_during = 0, ms_rebuild_during = 0;  // medians of the tearing step and the model rebuild
  double drop = 0;                                   // 1 - fps_during / fps_before
  std::string path;  // "device" (resident sheet, patched model, per-particle rebuild), "sorted" (the same with
                     // the radix-sort rebuild) or "host"
  // --profile: mean ms per frame of each stage in the before / during / after phases (first-seen order).
  std::vector<std::string> stage_order;
  std::map<std::string, double> stage_sum[3];
  int phase_frames[3] = {0, 0, 0};
};

struct Options {
  bool profile = false, host_path = false, sorted_rebuild = false, stages = false, no_graph = false;
  int summary_every = 1;
};

void addStages(Row& row, int phase, const TearFrameStats& st) {
  ++row.phase_frames[phase];
  for (const StageTime& s : st.stages) {
    if (!row.stage_sum[0].count(s.stage) && !row.stage_sum[1].count(s.stage) && !row.stage_sum[2].count(s.stage))
      row.stage_order.push_back(s.stage);
    row.stage_sum[phase][s.stage] += s.ms;
  }
}

void printStages(const Row& row, bool synchronised) {
  std::printf("  stages (%s %s %lld, %s path; mean ms per frame, %s):\n", row.backend.c_str(), row.method.c_str(),
              (long long)row.target, row.path.c_str(),
              synchronised ? "synchronised per stage" : "host wall time, device work not synchronised");
  std::printf("  %-28s %10s %10s %10s\n", "stage", "before", "during", "after");
  for (const std::string& name : row.stage_order) {
    double v[3];
    for (int k = 0; k < 3; ++k) {
      const auto it = row.stage_sum[k].find(name);
      v[k] = (it == row.stage_sum[k].end() || row.phase_frames[k] == 0) ? 0.0 : it->second / row.phase_frames[k];
    }
    std::printf("  %-28s %10.4f %10.4f %10.4f\n", name.c_str(), v[0], v[1], v[2]);
  }
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

using Clock = std::chrono::steady_clock;

// The paper's leg: skin as an open tube, radius 6 cm, length 60 cm, ends held; spacing from the particle count.
TearSheet<float> legSkin(std::int64_t particles, double& h) {
  const double r = 0.06, len = 0.6;
  h = std::sqrt(6.283185307179586 * r * len / double(particles));
  const int na = std::max(8, int(std::lround(6.283185307179586 * r / h)));
  const int nl = std::max(4, int(std::lround(len / h)) + 1);
  TearSheet<float> s = makeTearTube<float>(na, nl, r, len, 1100.0 * 0.002, 1.5e4, 1.5e3);
  fixTearParticles(s, Vec3d(-1, -1, -1), Vec3d(1, 1, 0.5 * h));
  fixTearParticles(s, Vec3d(-1, -1, len - 0.5 * h), Vec3d(1, 1, 1));
  return s;
}

Row runCase(BackendKind backend, TearCriterion crit, std::int64_t particles, std::int64_t target, int f_before,
            int f_during, int f_after, const Options& opt) {
  double h = 0;
  TearSheet<float> s = legSkin(particles, h);
  // A square patch on the front of the thigh holding about `target` particles.
  const double side = h * std::sqrt(double(target));
  const auto mark = markInBox(s, Vec3d(0.0, -0.5 * side, 0.3 - 0.5 * side), Vec3d(1.0, 0.5 * side, 0.3 + 0.5 * side));
  TearParams<float> tp;
  tp.criterion = crit;
  tp.break_strain = 0.2f;  // traditional at the same stress scale: k * 0.2 = 2 tau_f
  tp.seed = 1;
  TearModelOptions mo;
  mo.stretch_compliance = 1e-4;
  mo.bending_compliance = 10.0;
  mo.device_sorted_rebuild = opt.sorted_rebuild;
  PbdStepParams<float> sp;
  sp.gravity = Vec3f(0, 0, 0);
  sp.substeps = 4;
  sp.iterations = 5;
  sp.damping = 2.0f;
  sp.volume_preservation = false;
  sp.use_graph = !opt.no_graph;
  TearingDriver<float> d(s, tp, mo, sp, backend);
  if (opt.host_path) {
    d.allow_device_resident = false;
    d.resetModel();
  }
  d.setSummaryEvery(opt.summary_every);
  d.profile = opt.profile;
  Row row;
  row.path = d.deviceResident() ? (opt.sorted_rebuild ? "sorted" : "device") : "host";
  row.backend = backendName(d.kind());
  row.method = tearCriterionName(crit);
  row.particles = std::int64_t(d.sheet().size());
  row.target = target;
  std::vector<std::int32_t> ids;
  std::vector<Vec3f> base;
  for (std::size_t i = 0; i < mark.size(); ++i)
    if (mark[i]) {
      ids.push_back(std::int32_t(i));
      base.push_back(d.sheet().x[i]);
    }
  row.gripped = std::int64_t(ids.size());
  auto frame = [&](const std::vector<std::int32_t>& g, const std::vector<Vec3f>& to, TearFrameStats* st) {
    const auto t0 = Clock::now();
    const TearFrameStats r = d.advance(g, to);
    if (st) *st = r;
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  };
  std::vector<double> before, during, after, tear_ms, rebuild_ms;
  frame({}, {}, nullptr);  // warm-up
  TearFrameStats st;
  for (int f = 0; f < f_before; ++f) {
    before.push_back(frame({}, {}, &st));
    addStages(row, 0, st);
  }
  // During: the patch is gripped and pulled 3 cm outwards (+x) over the frames while the criterion tears the
  // tissue around it; at the last frame it is removed.
  std::vector<Vec3f> to(ids.size());
  for (int f = 0; f < f_during; ++f) {
    const float a = float(f + 1) / float(f_during);
    for (std::size_t k = 0; k < ids.size(); ++k) to[k] = base[k] + Vec3f(0.03f * a, 0, 0);
    double ms = frame(ids, to, &st);
    addStages(row, 1, st);
    row.splits += st.splits;
    tear_ms.push_back(st.tear_ms);
    rebuild_ms.push_back(st.rebuild_ms);
    if (f + 1 == f_during) {
      const auto t0 = Clock::now();
      std::vector<std::uint8_t> grip(d.particleCount(), 0);
      for (std::int32_t id : ids) grip[id] = 1;
      d.removeParticles(grip);
      ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    }
    during.push_back(ms);
  }
  for (int f = 0; f < f_after; ++f) {
    after.push_back(frame({}, {}, &st));
    addStages(row, 2, st);
  }
  row.particles_after = std::int64_t(d.particleCount());
  row.ms_before = median(before);
  row.ms_during = median(during);
  row.ms_during_max = during.empty() ? 0 : *std::max_element(during.begin(), during.end());
  row.ms_after = median(after);
  row.ms_tear_during = median(tear_ms);
  row.ms_rebuild_during = median(rebuild_ms);
  row.drop = row.ms_during > 0 ? 1.0 - row.ms_before / row.ms_during : 0;
  return row;
}

std::vector<std::int64_t> parseList(const std::string& text) {
  std::vector<std::int64_t> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) {
      long long x = 0;
      try {
        x = std::stoll(item);
      } catch (const std::exception&) {
        throw InputError("command line", "--tears", "not an integer list: " + text);
      }
      if (x < 1) throw InputError("command line", "--tears", "counts must be >= 1");
      v.push_back(x);
    }
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Tearing frame time: leg skin, traditional vs Tresca, before/during/after"};
  std::string backend_text = "both", tears_text = "200,4000", csv;
  std::int64_t particles = 150000, cpu_max = 1000000;
  int f_before = 30, f_during = 60, f_after = 30;
  bool quick = false;
  Options opt;
  app.add_option("--backend", backend_text, "cpu | cuda | both (cuda rows only with a device)");
  app.add_option("--particles", particles, "skin particles (the paper: ~150000)");
  app.add_option("--tears", tears_text, "particles gripped and torn out, comma separated (the paper: 200,4000)");
  app.add_option("--cpu-max", cpu_max, "skip CPU rows above this many particles");
  app.add_option("--frames-before", f_before, "frames timed before the tear");
  app.add_option("--frames-during", f_during, "frames of the tear (the paper: 2 s)");
  app.add_option("--frames-after", f_after, "frames timed after the tear");
  app.add_option("--csv", csv, "write the rows as CSV here");
  app.add_flag("--quick", quick, "a short run: 20000 particles, tears 200,1000, 5/10/5 frames");
  app.add_flag("--profile", opt.profile,
               "per-stage breakdown (device work synchronised around each stage, PBD stages by CUDA events; slower)");
  app.add_flag("--stages", opt.stages,
               "print the coarse stages' host wall time per phase (no synchronisation added: what --profile perturbs)");
  app.add_flag("--host-path", opt.host_path,
               "CUDA: host sheet + host model rebuild every tearing frame (the old path)");
  app.add_flag("--sorted-rebuild", opt.sorted_rebuild,
               "CUDA device path: re-derive the topology by the older radix sorts instead of per particle");
  app.add_flag("--no-graph", opt.no_graph,
               "CUDA: launch every PBD frame directly (no CUDA graph), to measure the graph's part");
  app.add_option("--summary-every", opt.summary_every, "CUDA: PBD residual/finiteness summary every N frames");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (quick) {
      particles = std::min<std::int64_t>(particles, 20000);
      tears_text = "200,1000";
      f_before = 5;
      f_during = 10;
      f_after = 5;
    }
    if (particles < 100) throw InputError("command line", "--particles", "must be >= 100");
    if (f_before < 1 || f_during < 1 || f_after < 1) throw InputError("command line", "--frames-*", "must be >= 1");
    if (opt.summary_every < 1) throw InputError("command line", "--summary-every", "must be >= 1");
    const std::vector<std::int64_t> tears = parseList(tears_text);
    std::vector<BackendKind> backends;
    bool have_cuda = false;
#if INCISION_HAVE_CUDA
    have_cuda = cuda::queryDevices().device_count > 0;
#endif
    if (backend_text == "cpu" || backend_text == "both") backends.push_back(BackendKind::Cpu);
    if ((backend_text == "cuda" || backend_text == "both") && have_cuda) backends.push_back(BackendKind::Cuda);
    if (backend_text == "cuda" && !have_cuda) throw InputError("command line", "--backend", "no CUDA device");
    if (backend_text != "cpu" && backend_text != "cuda" && backend_text != "both")
      throw InputError("command line", "--backend", "expected cpu, cuda or both");
    std::vector<Row> rows;
    std::printf("%-5s %-12s %9s %6s %7s %7s %9s %9s %9s %9s %8s %8s %7s %6s\n", "tear", "method", "particles", "target",
                "gripped", "splits", "ms_before", "ms_during", "ms_max", "ms_after", "tear_ms", "rebld_ms", "drop",
                "path");
    for (BackendKind b : backends) {
      if (b == BackendKind::Cpu && particles > cpu_max) continue;
      for (std::int64_t t : tears)
        for (TearCriterion c : {TearCriterion::Threshold, TearCriterion::TrescaBonds, TearCriterion::TrescaPrincipal}) {
          const Row r = runCase(b, c, particles, t, f_before, f_during, f_after, opt);
          rows.push_back(r);
          std::printf("%-5s %-12s %9lld %6lld %7lld %7lld %9.3f %9.3f %9.3f %9.3f %8.3f %8.3f %6.1f%% %6s\n",
                      r.backend.c_str(), r.method.c_str(), (long long)r.particles, (long long)r.target,
                      (long long)r.gripped, (long long)r.splits, r.ms_before, r.ms_during, r.ms_during_max, r.ms_after,
                      r.ms_tear_during, r.ms_rebuild_during, 100.0 * r.drop, r.path.c_str());
          if (opt.profile || opt.stages) printStages(r, opt.profile);
          std::fflush(stdout);
        }
    }
    if (!csv.empty()) {
      std::ofstream f(csv);
      if (!f) throw InputError(csv, "--csv", "cannot write the file");
      f << "backend,method,particles,target,gripped,splits,particles_after,ms_before,ms_during,ms_during_max,ms_after,"
           "ms_tear_during,ms_rebuild_during,drop,path\n";
      for (const Row& r : rows)
        f << r.backend << ',' << r.method << ',' << r.particles << ',' << r.target << ',' << r.gripped << ','
          << r.splits << ',' << r.particles_after << ',' << r.ms_before << ',' << r.ms_during << ',' << r.ms_during_max
          << ',' << r.ms_after << ',' << r.ms_tear_during << ',' << r.ms_rebuild_during << ',' << r.drop << ','
          << r.path << '\n';
    }
    // Summary: the worst Tresca drop and its frame time during the largest tear, per backend.
    std::ostringstream sum;
    sum << "bench_tearing: " << particles << " particles;";
    for (const Row& r : rows)
      if (r.method == "tresca" && r.target == tears.back())
        sum << ' ' << r.backend << " tresca " << r.target << ": " << r.ms_before << " -> " << r.ms_during
            << " ms/frame (drop " << int(std::lround(100 * r.drop)) << "%);";
    for (const Row& r : rows)
      if (r.method == "traditional" && r.target == tears.back())
        sum << ' ' << r.backend << " traditional: drop " << int(std::lround(100 * r.drop)) << "%;";
    std::printf("%s\n", sum.str().c_str());
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  }
  return 0;
}
