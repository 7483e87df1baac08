// The speed/accuracy sweep: one knob at a time per model, timed frames, error vs an analytic or converged reference.
#include "host/app/tradeoff.h"
#include "host/scene/scene_compile.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <sstream>

#include "host/app/runner.h"
#include "host/backends/backend_choice.h"
#include "host/haptics/mfs_punch.h"
#include "host/sim/metaball_simulation.h"
#include "model/input_error.h"

namespace inc {
namespace {

struct Measured {
  std::size_t particles = 0;
  double wall_ms = 0.0, cpu_ms = 0.0;
  double setup_s = 0.0;
  double observable = 0.0;
  bool finite = true;
  bool held = true;
  bool settled = true;
  int frames = 0;  // frames run
  std::string note;
};

// How long a measurement runs: at least `min_frames`, then until the observable has moved by at most `tolerance` of
// its value over the last `window` frames (settled), or `max_frames` (not settled: said in the row's note). A fixed
// frame count measured mid-transient: issue 31 saw --quick report 9.45 % where the settled error was 43.9 %.
struct SettleRule {
  int min_frames = 4;
  int max_frames = 400;
  int window = 10;
  double tolerance = 1e-3;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double processCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

// Builds the scene's (single) model through the factory, runs it until it settles (SettleRule), times each advance().
Measured measure(const Scene& s, BackendKind backend, const SettleRule& rule, const AnalyticCase& ac) {
  Measured m;
  std::vector<std::unique_ptr<SimulationModel>> models;
  const auto t_build = std::chrono::steady_clock::now();
  try {
    models = createSceneModels(compileScene(s), backend);
  } catch (const InputError& e) {
    m.finite = false;
    m.note = std::string("refused: ") + e.what();
    return m;
  }
  m.setup_s = secondsSince(t_build);
  if (models.size() != 1) throw InputError(s.file, "models", "tradeoff needs exactly one model per run");
  SimulationModel& model = *models[0];
  m.particles = model.particleCount();
  std::vector<Vec3d> rest, now;
  model.currentPositions(rest);
  // Fixed boxes select particles (sphere centres) by their rest position: a coarse or packed body can have
  // none inside, and then it falls. Said in the row, since the error alone does not say why.
  if (!s.fixed.empty()) {
    std::size_t held = 0;
    for (const Vec3d& p : rest)
      for (const FixedRegion& f : s.fixed)
        if (p.x >= f.min.x && p.x <= f.max.x && p.y >= f.min.y && p.y <= f.max.y && p.z >= f.min.z && p.z <= f.max.z) {
          ++held;
          break;
        }
    if (held == 0) {
      m.held = false;
      m.note = "no particle or sphere centre lies in a fixed box: the body is not held";
    }
  }
  std::vector<double> ms, cpu, history;
  m.settled = false;
  for (int f = 0; f < rule.max_frames && !m.settled; ++f) {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = processCpuMs();
    const FrameReport rep = model.advance(s.solver.frame_dt);
    cpu.push_back(processCpuMs() - c0);
    ms.push_back(1e3 * secondsSince(t0));
    m.frames = f + 1;
    if (!rep.finite) {
      m.finite = false;
      m.note = "non-finite at frame " + std::to_string(f) + ", stage " + rep.failure_stage + ", particle " +
               std::to_string(rep.failure_particle);
      break;
    }
    model.currentPositions(now);
    history.push_back(analyticObservable(ac, rest, now, s.geometry.spacing));
    const std::size_t k = history.size();
    // A body no fixed box holds falls and has no static answer to wait for: measured at min_frames, said in the note.
    if (!m.held && int(k) >= rule.min_frames) break;
    if (int(k) >= rule.min_frames && int(k) > rule.window) {
      const double change = std::abs(history[k - 1] - history[k - 1 - std::size_t(rule.window)]);
      m.settled = change <= rule.tolerance * std::abs(history[k - 1]);
    }
  }
  if (m.finite && m.held && !m.settled) {
    const std::size_t k = history.size();
    const double change = k > std::size_t(rule.window)
                              ? std::abs(history[k - 1] - history[k - 1 - std::size_t(rule.window)]) /
                                    std::max(std::abs(history[k - 1]), 1e-300)
                              : 1.0;
    m.note = "not settled after " + std::to_string(m.frames) + " frames (still moving " +
             std::to_string(100.0 * change) + " % per " + std::to_string(rule.window) +
             " frames): the error is of a moving body";
  }
  // The first frame pays one-off costs (neighbour build, allocation): leave it out when there are others.
  if (ms.size() > 1) {
    ms.erase(ms.begin());
    cpu.erase(cpu.begin());
  }
  m.wall_ms = median(ms);
  m.cpu_ms = median(cpu);
  model.currentPositions(now);
  m.observable = analyticObservable(ac, rest, now, s.geometry.spacing);
  if (!std::isfinite(m.observable)) {
    m.finite = false;
    if (m.note.empty()) m.note = "non-finite positions";
  }
  return m;
}

std::string fmt(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

}  // namespace

std::vector<TradeoffSetting> tradeoffSettings(const Scene& base, const std::string& model, bool quick) {
  std::vector<TradeoffSetting> out;
  auto add = [&](const std::string& knob, const std::string& value, Scene s) {
    out.push_back({knob, value, std::move(s)});
  };
  add("baseline", "", base);
  const std::vector<double> spacing_f = quick ? std::vector<double>{1.5} : std::vector<double>{2.0, 1.5, 0.75, 0.5};
  const Precision other = base.solver.precision == Precision::Float32 ? Precision::Float64 : Precision::Float32;
  if (model == "mls") {
    for (double f : spacing_f) {
      Scene s = base;
      s.geometry.spacing *= f;
      add("spacing", fmt(s.geometry.spacing), s);
    }
    for (double sf : quick ? std::vector<double>{1.5} : std::vector<double>{1.5, 2.5, 3.0}) {
      if (std::abs(sf - base.mls.support_factor) < 1e-9) continue;
      Scene s = base;
      s.mls.support_factor = sf;
      add("support_factor", fmt(sf), s);
    }
    for (double sa : quick ? std::vector<double>{0.9} : std::vector<double>{0.9, 0.25, 0.1}) {
      if (std::abs(sa - base.solver.safety) < 1e-9) continue;
      Scene s = base;
      s.solver.safety = sa;
      add("safety", fmt(sa), s);
    }
  } else {
    for (int it : quick ? std::vector<int>{2} : std::vector<int>{1, 2, 5, 20, 40}) {
      if (it == base.pbd.iterations) continue;
      Scene s = base;
      s.pbd.iterations = it;
      add("iterations", std::to_string(it), s);
    }
    const int base_sub = base.solver.substeps > 0 ? base.solver.substeps : 4;
    for (int sub : quick ? std::vector<int>{1} : std::vector<int>{1, 2, 8, 16}) {
      if (sub == base_sub) continue;
      Scene s = base;
      s.solver.substeps = sub;
      add("substeps", std::to_string(sub), s);
    }
    // Solver: the other projection order, and Jacobi with Chebyshev acceleration (docs/pbd.md) at the scene's
    // iterations, so a user sees what the acceleration buys on their own organ.
    if (!quick) {
      Scene s = base;
      s.pbd.solver = base.pbd.solver == "jacobi" ? "gauss_seidel" : "jacobi";
      s.pbd.chebyshev_rho = 0;
      add("solver", s.pbd.solver, s);
    }
    for (double rho : quick ? std::vector<double>{0.9} : std::vector<double>{0.5, 0.9}) {
      if (base.pbd.solver == "jacobi" && rho == base.pbd.chebyshev_rho) continue;
      Scene s = base;
      s.pbd.solver = "jacobi";
      s.pbd.chebyshev_rho = rho;
      add("chebyshev_rho", fmt(rho) + (base.pbd.solver == "jacobi" ? "" : " (jacobi)"), s);
    }
    // Sphere count. A lattice organ (pbd.target_spheres = 0) changes it through the lattice spacing and, as a
    // second knob, through the packer at a fraction of its lattice count; a packed organ through the packer
    // only (its spheres do not depend on geometry.spacing).
    const bool packed = base.pbd.target_spheres > 0;
    if (!packed)
      for (double f : spacing_f) {
        Scene s = base;
        s.geometry.spacing *= f;
        add("spheres", "", s);  // value: the sphere count, filled in after the build
      }
    const int n0 = packed ? base.pbd.target_spheres : int(buildSceneMetaballs(compileScene(base)).size());
    const std::vector<double> fractions =
        packed ? (quick ? std::vector<double>{0.5} : std::vector<double>{0.25, 0.5, 2.0})
               : (quick ? std::vector<double>{0.25} : std::vector<double>{0.125, 0.25, 0.5, 1.0});
    for (double f : fractions) {
      Scene s = base;
      s.pbd.target_spheres = std::max(8, int(std::lround(f * n0)));
      add("target_spheres", std::to_string(s.pbd.target_spheres), s);
    }
  }
  Scene s = base;
  s.solver.precision = other;
  add("precision", precisionName(other), s);
  return out;
}

Scene tradeoffReferenceScene(const Scene& base, const std::string& model, bool quick) {
  Scene s = base;
  s.solver.precision = Precision::Float64;
  if (model == "pbd" && base.pbd.target_spheres > 0)
    s.pbd.target_spheres = base.pbd.target_spheres * (quick ? 1 : 2);  // a packed organ: twice the spheres
  else
    s.geometry.spacing *= quick ? 1.0 : 0.5;
  if (model == "mls") {
    s.solver.safety = std::min(base.solver.safety, quick ? 0.5 : 0.1);
  } else {
    s.pbd.iterations = std::max(base.pbd.iterations, quick ? 10 : 40);
    s.solver.substeps = quick ? 4 : 16;
  }
  return s;
}

namespace {

// The node-count knob of the haptic local model on the flat punch (host/haptics/mfs_punch.h).
void sweepMfs(const Scene& scene, bool quick, bool cpu_cost, TradeoffResult& res) {
  MfsPunchSpec spec;
  for (const ToolSpec& t : scene.tools)
    if ((t.kind == "probe" || t.kind == "grasper") && t.radius > 0.0) {
      spec.radius_m = t.radius;
      break;
    }
  const Material& material = scene.material;
  const double delta = 1e-3 * spec.radius_m;
  const double reference = flatPunchForce(spec.radius_m, material.youngs_modulus_pa, material.poisson_ratio, delta);
  res.references.push_back(
      "mfs: flat rigid punch on a half-space, F = 2 a E delta / (1 - nu^2) (a = " + fmt(spec.radius_m * 1e3) +
      " mm, delta = " + fmt(delta * 1e6) + " um, E = " + fmt(material.youngs_modulus_pa) +
      " Pa, nu = " + fmt(material.poisson_ratio) + "): " + fmt(reference) + " N; MFS half-ball of radius " +
      fmt(spec.domain_over_radius) + " a held at its outer shell; cost: ms per haptic tick");
  for (int shells : quick ? std::vector<int>{1} : std::vector<int>{1, 2, 3, 4}) {
    spec.contact_shells = shells;
    TradeoffRow row;
    row.model = "mfs";
    row.knob = "nodes";
    row.unit = "N";
    try {
      const MfsPunchResult r = mfsFlatPunch(spec, material);
      row.value = std::to_string(r.nodes);
      row.particles = std::size_t(r.nodes);
      row.wall_ms = r.tick_ms;
      row.cpu_ms = r.tick_cpu_ms;
      row.ms_per_frame = cpu_cost ? r.tick_cpu_ms : r.tick_ms;
      row.setup_s = r.setup_s;
      row.observable = r.force_n;
      row.finite = std::isfinite(r.force_n);
      row.error = std::abs(r.force_n - reference) / reference;
      if (!row.finite) row.note = "non-finite force";
    } catch (const InputError& e) {
      row.value = std::to_string(shells) + " shells";
      row.finite = false;
      row.note = std::string("refused: ") + e.what();
    }
    if (!quick)
      std::fprintf(stderr, "tradeoff: mfs nodes %s: %.3g ms/tick, setup %.3g s, error %.3g\n", row.value.c_str(),
                   row.ms_per_frame, row.setup_s, row.error);
    res.rows.push_back(row);
  }
}

}  // namespace

std::vector<double> parseBudgets(const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end == item.c_str() || *end != '\0' || !(v > 0.0) || v > 1e9)
      throw InputError("", "--budget-ms", "'" + text + "' is not a comma list of positive ms values (e.g. 1,16)");
    out.push_back(v);
  }
  if (out.empty()) throw InputError("", "--budget-ms", "no budget given");
  return out;
}

std::string tradeoffCostName(const TradeoffOptions& options) { return options.cpu_cost ? "cpu" : "wall"; }

TradeoffResult runTradeoff(const Scene& scene, const TradeoffOptions& opt) {
  if (!scene.models.mls && !scene.models.pbd_metaballs && !scene.models.haptics)
    throw InputError(scene.file, "models",
                     "tradeoff sweeps the MLS, PBD and haptic (MFS) models; the scene switches on none of them");
  for (double b : opt.budgets_ms)
    if (!(b > 0.0) || !std::isfinite(b)) throw InputError("", "--budget-ms", "budgets must be positive numbers of ms");
  const BackendChoice choice = resolveBackend(opt.backend);
  TradeoffResult res;
  res.scene = scene.name;
  res.backend = backendName(choice.kind);
  res.cost = tradeoffCostName(opt);

  Scene base = scene;
  base.tools.clear();
  base.models.cutting = base.models.tearing = base.models.haptics = false;
  const AnalyticCase ac = detectAnalyticCase(base);
  SettleRule rule;
  if (ac.kind != AnalyticCase::Kind::None) {
    // Critical damping of the first mode the load excites (mass-proportional damping leaves the static answer
    // unchanged and damps every mode at the same rate c / 2 = omega_1): the analytic transient is below 0.3 % of the
    // static answer after 8 / omega_1 s. A discrete model softer or stiffer than the analytic one rings at another
    // frequency (over- or under-damped), so the run goes on until the answer stops moving, judged over a quarter
    // of the analytic period.
    base.material.damping_per_s = 2.0 * ac.omega1;
    rule.min_frames = int(std::ceil(8.0 / ac.omega1 / base.solver.frame_dt));
    rule.window = std::max(2, int(std::ceil(0.5 * 3.14159265358979 / ac.omega1 / base.solver.frame_dt)));
  } else {
    rule.min_frames = int(std::ceil(std::min(base.duration, 0.25) / base.solver.frame_dt));
  }
  // --quick checks that every knob runs: few settings, a looser settle tolerance, but still a settled answer.
  rule.tolerance = opt.quick ? 1e-2 : 1e-3;
  rule.min_frames = std::max(rule.min_frames, 4);  // at least 3 timed frames
  rule.max_frames = std::max(rule.min_frames, opt.quick ? 200 : 2000);
  const std::string settle =
      "run until the answer moves less than " + fmt(100.0 * rule.tolerance) + " % in " + std::to_string(rule.window) +
      " frames (at least " + std::to_string(rule.min_frames) + ", at most " + std::to_string(rule.max_frames) +
      "), damping " +
      (ac.kind != AnalyticCase::Kind::None ? "2 omega_1 = " + fmt(base.material.damping_per_s) + " 1/s"
                                           : fmt(base.material.damping_per_s) + " 1/s (the scene's)");
  const std::string strain_note =
      ac.max_strain > 0.05 ? " (largest strain " + fmt(100.0 * ac.max_strain) + " %: beyond linear theory)" : "";

  for (const std::string model : {"mls", "pbd"}) {
    if ((model == "mls" && !scene.models.mls) || (model == "pbd" && !scene.models.pbd_metaballs)) continue;
    Scene m = base;
    m.models.mls = model == "mls";
    m.models.pbd_metaballs = model == "pbd";
    double reference = 0.0;
    if (model == "mls" && ac.kind != AnalyticCase::Kind::None) {
      reference = ac.reference_m;
      res.references.push_back("mls: " + ac.describe + strain_note + "; " + settle);
    } else {
      const Scene ref = tradeoffReferenceScene(m, model, opt.quick);
      const Measured r = measure(ref, choice.kind, rule, ac);
      if (!r.finite) throw InputError(scene.file, "tradeoff", "the reference run failed: " + r.note);
      // A reference that never settles is not a reference: the sweep would measure motion, not error.
      if (r.held && !r.settled) throw InputError(scene.file, "tradeoff", "the reference run did not settle: " + r.note);
      reference = r.observable;
      std::string what = model + ": float64 run at the finest setting (" +
                         (model == "pbd" && ref.pbd.target_spheres > 0
                              ? "packed to " + std::to_string(ref.pbd.target_spheres) + " spheres"
                              : "spacing " + fmt(ref.geometry.spacing) + " m") +
                         (model == "mls" ? ", safety " + fmt(ref.solver.safety)
                                         : ", " + std::to_string(ref.pbd.iterations) + " iterations, " +
                                               std::to_string(ref.solver.substeps) + " substeps") +
                         ", " + std::to_string(r.particles) + (model == "pbd" ? " spheres" : " particles") + "): " +
                         (ac.kind == AnalyticCase::Kind::Cantilever   ? "tip deflection "
                          : ac.kind == AnalyticCase::Kind::HangingBar ? "tip drop "
                                                                      : "centroid displacement ") +
                         fmt(reference * 1e3) + " mm; " + settle;
      // A PBD body with an analytic answer: say how far its converged run is from it (the lattice compliances
      // come from E by a rod rule, not from a continuum, so the sweep measures PBD against itself).
      if (ac.kind != AnalyticCase::Kind::None)
        what += "; the analytic answer is " + fmt(ac.reference_m * 1e3) + " mm (converged " + model + " differs by " +
                fmt(100.0 * std::abs(reference - ac.reference_m) / ac.reference_m) + " %)";
      res.references.push_back(what);
    }
    for (const TradeoffSetting& st : tradeoffSettings(m, model, opt.quick)) {
      const Measured r = measure(st.scene, choice.kind, rule, ac);
      TradeoffRow row;
      row.model = model;
      row.knob = st.knob;
      row.value = st.knob == "spheres" ? std::to_string(r.particles) : st.value;
      row.particles = r.particles;
      row.wall_ms = r.wall_ms;
      row.cpu_ms = r.cpu_ms;
      row.ms_per_frame = opt.cpu_cost ? r.cpu_ms : r.wall_ms;
      row.setup_s = r.setup_s;
      row.observable = r.observable;
      row.finite = r.finite;
      row.held = r.held;
      row.note = r.note;
      row.error =
          std::abs(reference) > 0.0 ? std::abs(r.observable - reference) / std::abs(reference) : std::abs(r.observable);
      if (!opt.quick)
        std::fprintf(stderr, "tradeoff: %s %s %s: %.3g ms/frame, setup %.3g s, error %.3g\n", model.c_str(),
                     row.knob.c_str(), row.value.c_str(), row.ms_per_frame, row.setup_s, row.error);
      res.rows.push_back(row);
    }
  }
  if (scene.models.haptics) sweepMfs(scene, opt.quick, opt.cpu_cost, res);
  return res;
}

std::vector<std::size_t> paretoFront(const std::vector<TradeoffRow>& rows, double budget_ms) {
  std::vector<std::size_t> front;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const TradeoffRow& a = rows[i];
    if (!a.finite || !a.held || a.ms_per_frame > budget_ms) continue;
    bool dominated = false;
    for (std::size_t j = 0; j < rows.size() && !dominated; ++j) {
      const TradeoffRow& b = rows[j];
      if (j == i || !b.finite || !b.held || b.ms_per_frame > budget_ms) continue;
      dominated = b.ms_per_frame <= a.ms_per_frame && b.error <= a.error &&
                  (b.ms_per_frame < a.ms_per_frame || b.error < a.error);
    }
    if (!dominated) front.push_back(i);
  }
  std::sort(front.begin(), front.end(),
            [&](std::size_t x, std::size_t y) { return rows[x].ms_per_frame < rows[y].ms_per_frame; });
  return front;
}

std::string tradeoffCsv(const TradeoffResult& r) {
  std::ostringstream o;
  o << "model,knob,value,particles,ms_per_frame,wall_ms,cpu_ms,setup_s,observable,unit,error,finite,held,note\n";
  for (const TradeoffRow& x : r.rows) {
    std::string note = x.note;
    std::replace(note.begin(), note.end(), ',', ';');
    std::replace(note.begin(), note.end(), '\n', ' ');
    // A refused or failed setting has no cost and no error: empty fields, not zeros.
    auto num = [&](double v) { return x.finite ? fmt(v) : std::string(); };
    o << x.model << ',' << x.knob << ',' << x.value << ',' << x.particles << ',' << num(x.ms_per_frame) << ','
      << num(x.wall_ms) << ',' << num(x.cpu_ms) << ',' << num(x.setup_s) << ',' << num(x.observable) << ',' << x.unit
      << ',' << num(x.error) << ',' << (x.finite ? 1 : 0) << ',' << (x.held ? 1 : 0) << ',' << note << '\n';
  }
  return o.str();
}

std::string tradeoffMarkdown(const TradeoffResult& r, const std::vector<double>& budgets_ms) {
  std::ostringstream o;
  o << "# Trade-off: " << r.scene << " (" << r.backend << ", cost: " << r.cost << " time)\n\nReferences:\n";
  for (const std::string& s : r.references) o << "- " << s << "\n";
  const char* header = "| model | knob | value | particles | ms | setup s | error |\n|---|---|---|---|---|---|---|\n";
  auto row = [&](const TradeoffRow& x) {
    o << "| " << x.model << " | " << x.knob << " | " << x.value << " | " << x.particles << " | "
      << (x.finite ? fmt(x.ms_per_frame) : "-") << " | " << (x.finite ? fmt(x.setup_s) : "-") << " | "
      << (x.finite ? fmt(100.0 * x.error) + " %" + (x.held ? "" : " (not held)") : "failed") << " |\n";
  };
  o << "\nms: " << (r.cost == "cpu" ? "CPU time of the process" : "wall time")
    << " per frame (mls, pbd) or per haptic tick (mfs), median; setup: building the model once (mfs: assembly "
       "and condensation, paid per contact configuration).\n";
  for (const std::string model : {"mls", "pbd", "mfs"}) {
    std::vector<TradeoffRow> rows;
    for (const TradeoffRow& x : r.rows)
      if (x.model == model) rows.push_back(x);
    if (rows.empty()) continue;
    const std::string per = model == "mfs" ? " ms per haptic tick" : " ms per frame";
    for (double b : budgets_ms) {
      o << "\n## " << model << ": Pareto-optimal settings within " << fmt(b) << per << "\n\n";
      const std::vector<std::size_t> front = paretoFront(rows, b);
      if (front.empty()) {
        o << "No setting fits this budget on this machine.\n";
        continue;
      }
      o << header;
      for (std::size_t i : front) row(rows[i]);
    }
  }
  o << "\n## All settings\n\n" << header;
  for (const TradeoffRow& x : r.rows) row(x);
  for (const TradeoffRow& x : r.rows)
    if (!x.note.empty()) o << "\n- " << x.model << " " << x.knob << " " << x.value << ": " << x.note;
  o << "\n";
  return o.str();
}

}  // namespace inc
