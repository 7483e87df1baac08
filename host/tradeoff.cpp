// The speed/accuracy sweep: one knob at a time per model, timed frames, error vs an analytic or converged reference.
#include "host/tradeoff.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "host/input_error.h"
#include "host/runner.h"

namespace inc {
namespace {

struct Measured {
  std::size_t particles = 0;
  double ms = 0.0;
  double observable = 0.0;
  bool finite = true;
  std::string note;
};

struct Cantilever {
  bool yes = false;
  double length = 0.0, width = 0.0, height = 0.0;
  double tip_x = 0.0;   // x of the free end
  double omega1 = 0.0;  // rad/s, first bending mode (EB)
};

// A beam/box clamped by one fixed box over its x-min end, gravity along -z, no tools (docs/tradeoff.md).
Cantilever detectCantilever(const Scene& s) {
  Cantilever c;
  const GeometrySpec& g = s.geometry;
  if (g.kind != GeometrySpec::Kind::Beam && g.kind != GeometrySpec::Kind::Box) return c;
  if (s.fixed.size() != 1 || !s.tools.empty()) return c;
  const Vec3d lo{g.center.x - 0.5 * g.size.x, g.center.y - 0.5 * g.size.y, g.center.z - 0.5 * g.size.z};
  const Vec3d hi{g.center.x + 0.5 * g.size.x, g.center.y + 0.5 * g.size.y, g.center.z + 0.5 * g.size.z};
  const FixedRegion& f = s.fixed[0];
  const bool covers_end = f.min.x <= lo.x && f.max.x > lo.x && f.max.x < lo.x + 0.5 * g.size.x && f.min.y <= lo.y &&
                          f.max.y >= hi.y && f.min.z <= lo.z && f.max.z >= hi.z;
  const Vec3d gr = s.solver.gravity;
  if (!covers_end || std::abs(gr.x) > 1e-12 || std::abs(gr.y) > 1e-12 || gr.z >= 0.0) return c;
  c.yes = true;
  c.length = hi.x - f.max.x;
  c.width = g.size.y;
  c.height = g.size.z;
  c.tip_x = hi.x;
  const double E = s.material.youngs_modulus, rho = s.material.density;
  // omega_1 = (1.8751)^2 sqrt(E I / (rho A)) / L^2, I / A = h^2 / 12 (first root of 1 + cos k cosh k = 0).
  c.omega1 = 1.8751 * 1.8751 * std::sqrt(E * c.height * c.height / (12.0 * rho)) / (c.length * c.length);
  return c;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Builds the scene's (single) model through the factory, runs `frames` frames, times each advance().
Measured measure(const Scene& s, BackendKind backend, int frames, const Cantilever& cant) {
  Measured m;
  std::vector<std::unique_ptr<SimulationModel>> models;
  try {
    models = createSceneModels(s, backend);
  } catch (const InputError& e) {
    m.finite = false;
    m.note = std::string("refused: ") + e.what();
    return m;
  }
  if (models.size() != 1) throw InputError(s.file, "models", "tradeoff needs exactly one model per run");
  SimulationModel& model = *models[0];
  m.particles = model.particleCount();
  std::vector<Vec3d> rest, now;
  model.currentPositions(rest);
  std::vector<double> ms;
  for (int f = 0; f < frames; ++f) {
    const auto t0 = std::chrono::steady_clock::now();
    const FrameReport rep = model.advance(s.solver.frame_dt);
    const auto t1 = std::chrono::steady_clock::now();
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    if (!rep.finite) {
      m.finite = false;
      m.note = "non-finite at frame " + std::to_string(f) + ", stage " + rep.failure_stage + ", particle " +
               std::to_string(rep.failure_particle);
      break;
    }
  }
  // The first frame pays one-off costs (neighbour build, allocation): leave it out when there are others.
  if (ms.size() > 1) ms.erase(ms.begin());
  m.ms = median(ms);
  model.currentPositions(now);
  if (cant.yes) {
    // Tip deflection: mean downward displacement of the particles in the last lattice layer.
    double sum = 0.0;
    int n = 0;
    double x_end = -1e300;
    for (const Vec3d& p : rest) x_end = std::max(x_end, p.x);
    for (std::size_t i = 0; i < rest.size() && i < now.size(); ++i)
      if (rest[i].x >= x_end - 0.25 * s.geometry.spacing) {
        sum += rest[i].z - now[i].z;
        ++n;
      }
    m.observable = n > 0 ? sum / n : 0.0;
  } else {
    Vec3d d{0, 0, 0};
    for (std::size_t i = 0; i < rest.size() && i < now.size(); ++i) d = d + (now[i] - rest[i]);
    const double inv = rest.empty() ? 0.0 : 1.0 / double(rest.size());
    m.observable = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z) * inv;
  }
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

struct Setting {
  std::string knob, value;
  Scene scene;
};

std::vector<Setting> sweep(const Scene& base, const std::string& model, bool quick) {
  std::vector<Setting> out;
  auto add = [&](const std::string& knob, const std::string& value, Scene s) { out.push_back({knob, value, std::move(s)}); };
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
    for (double f : spacing_f) {
      Scene s = base;
      s.geometry.spacing *= f;
      add("spheres", "", s);  // value: the sphere count, filled in after the build
    }
  }
  Scene s = base;
  s.solver.precision = other;
  add("precision", precisionName(other), s);
  return out;
}

// The float64 run at the finest setting of the sweep: the reference where no analytic answer exists.
Scene finestScene(const Scene& base, const std::string& model, bool quick) {
  Scene s = base;
  s.solver.precision = Precision::Float64;
  s.geometry.spacing *= quick ? 1.0 : 0.5;
  if (model == "mls") {
    s.solver.safety = std::min(base.solver.safety, quick ? 0.5 : 0.1);
  } else {
    s.pbd.iterations = std::max(base.pbd.iterations, quick ? 10 : 40);
    s.solver.substeps = quick ? 4 : 16;
  }
  return s;
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

double eulerBernoulliTipDeflection(double length, double width, double height, double youngs, double density,
                                   double gravity) {
  const double q = density * gravity * width * height;      // N/m
  const double I = width * height * height * height / 12.0;  // m^4
  return q * std::pow(length, 4) / (8.0 * youngs * I);
}

TradeoffResult runTradeoff(const Scene& scene, const TradeoffOptions& opt) {
  if (!scene.models.mls && !scene.models.pbd_metaballs)
    throw InputError(scene.file, "models", "tradeoff sweeps the MLS and PBD models; the scene switches on neither");
  for (double b : opt.budgets_ms)
    if (!(b > 0.0) || !std::isfinite(b)) throw InputError("", "--budget-ms", "budgets must be positive numbers of ms");
  const BackendChoice choice = resolveBackend(opt.backend);
  TradeoffResult res;
  res.scene = scene.name;
  res.backend = backendName(choice.kind);

  Scene base = scene;
  base.tools.clear();
  base.models.cutting = base.models.tearing = base.models.haptics = false;
  const Cantilever cant = detectCantilever(base);
  int frames = 0;
  if (cant.yes) {
    // Critical damping of the first bending mode (mass-proportional damping leaves the static answer
    // unchanged) and 8 / omega_1 s: the transient is below 0.3 % of the sag by then.
    base.material.damping = 2.0 * cant.omega1;
    frames = int(std::ceil(8.0 / cant.omega1 / base.solver.frame_dt));
  } else {
    frames = int(std::ceil(std::min(base.duration, 0.25) / base.solver.frame_dt));
  }
  if (opt.quick) frames = std::min(frames, 4);
  frames = std::max(frames, 2);

  for (const std::string model : {"mls", "pbd"}) {
    if ((model == "mls" && !scene.models.mls) || (model == "pbd" && !scene.models.pbd_metaballs)) continue;
    Scene m = base;
    m.models.mls = model == "mls";
    m.models.pbd_metaballs = model == "pbd";
    double reference = 0.0;
    if (model == "mls" && cant.yes) {
      reference = eulerBernoulliTipDeflection(cant.length, cant.width, cant.height, m.material.youngs_modulus,
                                              m.material.density, -m.solver.gravity.z);
      res.references.push_back("mls: Euler-Bernoulli tip deflection of the cantilever (L = " + fmt(cant.length) +
                               " m, b = " + fmt(cant.width) + " m, h = " + fmt(cant.height) + " m): " +
                               fmt(reference * 1e3) + " mm; " + std::to_string(frames) +
                               " frames, damping 2 omega_1 = " + fmt(base.material.damping) + " 1/s");
    } else {
      const Scene ref = finestScene(m, model, opt.quick);
      const Measured r = measure(ref, choice.kind, frames, cant);
      if (!r.finite) throw InputError(scene.file, "tradeoff", "the reference run failed: " + r.note);
      reference = r.observable;
      res.references.push_back(model + ": float64 run at the finest setting (spacing " + fmt(ref.geometry.spacing) +
                               " m" + (model == "mls" ? ", safety " + fmt(ref.solver.safety)
                                                       : ", " + std::to_string(ref.pbd.iterations) + " iterations, " +
                                                             std::to_string(ref.solver.substeps) + " substeps") +
                               ", " + std::to_string(r.particles) + " particles): " +
                               (cant.yes ? "tip deflection " : "centroid displacement ") + fmt(reference * 1e3) +
                               " mm after " + std::to_string(frames) + " frames");
    }
    for (const Setting& st : sweep(m, model, opt.quick)) {
      const Measured r = measure(st.scene, choice.kind, frames, cant);
      TradeoffRow row;
      row.model = model;
      row.knob = st.knob;
      row.value = st.knob == "spheres" ? std::to_string(r.particles) : st.value;
      row.particles = r.particles;
      row.ms_per_frame = r.ms;
      row.observable = r.observable;
      row.finite = r.finite;
      row.note = r.note;
      row.error = std::abs(reference) > 0.0 ? std::abs(r.observable - reference) / std::abs(reference)
                                            : std::abs(r.observable);
      if (!opt.quick) std::fprintf(stderr, "tradeoff: %s %s %s: %.3g ms/frame, error %.3g\n", model.c_str(),
                                   row.knob.c_str(), row.value.c_str(), row.ms_per_frame, row.error);
      res.rows.push_back(row);
    }
  }
  return res;
}

std::vector<std::size_t> paretoFront(const std::vector<TradeoffRow>& rows, double budget_ms) {
  std::vector<std::size_t> front;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const TradeoffRow& a = rows[i];
    if (!a.finite || a.ms_per_frame > budget_ms) continue;
    bool dominated = false;
    for (std::size_t j = 0; j < rows.size() && !dominated; ++j) {
      const TradeoffRow& b = rows[j];
      if (j == i || !b.finite || b.ms_per_frame > budget_ms) continue;
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
  o << "model,knob,value,particles,ms_per_frame,observable_m,error,finite,note\n";
  for (const TradeoffRow& x : r.rows) {
    std::string note = x.note;
    std::replace(note.begin(), note.end(), ',', ';');
    std::replace(note.begin(), note.end(), '\n', ' ');
    o << x.model << ',' << x.knob << ',' << x.value << ',' << x.particles << ',' << fmt(x.ms_per_frame) << ','
      << fmt(x.observable) << ',' << fmt(x.error) << ',' << (x.finite ? 1 : 0) << ',' << note << '\n';
  }
  return o.str();
}

std::string tradeoffMarkdown(const TradeoffResult& r, const std::vector<double>& budgets_ms) {
  std::ostringstream o;
  o << "# Trade-off: " << r.scene << " (" << r.backend << ")\n\nReferences:\n";
  for (const std::string& s : r.references) o << "- " << s << "\n";
  auto row = [&](const TradeoffRow& x) {
    o << "| " << x.model << " | " << x.knob << " | " << x.value << " | " << x.particles << " | " << fmt(x.ms_per_frame)
      << " | " << (x.finite ? fmt(100.0 * x.error) + " %" : "failed") << " |\n";
  };
  for (const std::string model : {"mls", "pbd"}) {
    std::vector<TradeoffRow> rows;
    for (const TradeoffRow& x : r.rows)
      if (x.model == model) rows.push_back(x);
    if (rows.empty()) continue;
    for (double b : budgets_ms) {
      o << "\n## " << model << ": Pareto-optimal settings within " << fmt(b) << " ms per frame\n\n";
      const std::vector<std::size_t> front = paretoFront(rows, b);
      if (front.empty()) {
        o << "No setting fits this budget on this machine.\n";
        continue;
      }
      o << "| model | knob | value | particles | ms/frame | error |\n|---|---|---|---|---|---|\n";
      for (std::size_t i : front) row(rows[i]);
    }
  }
  o << "\n## All settings\n\n| model | knob | value | particles | ms/frame | error |\n|---|---|---|---|---|---|\n";
  for (const TradeoffRow& x : r.rows) row(x);
  for (const TradeoffRow& x : r.rows)
    if (!x.note.empty()) o << "\n- " << x.model << " " << x.knob << " " << x.value << ": " << x.note;
  o << "\n";
  return o.str();
}

}  // namespace inc
