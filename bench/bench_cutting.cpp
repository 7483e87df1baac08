// Cutting cost: frame time while the MLS nodal points are coupled with the spheres, the re-packing, and how the
// frame time grows with the cut length (the number of nodal points), per organ size and backend.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "cpu_fallback/mls_pair_sums_cpu.h"
#include "host/backends/backend_choice.h"
#include "host/scene/scene_compile.h"
#include "host/sim/dissection_simulation.h"
#include "model/backend.h"
#include "model/input_error.h"
#if INCISION_HAVE_CUDA
#include "kernels/device_info.h"
#endif

using namespace inc;

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
double stage(const FrameReport& r, const std::string& name) {
  double ms = 0;
  for (const auto& s : r.stages)
    if (s.stage == name) ms += s.ms;
  return ms;
}
double pbdStages(const FrameReport& r) {  // everything that is not a cut / MLS / coupling stage
  double ms = 0;
  for (const auto& s : r.stages)
    if (s.stage.rfind("cut_", 0) != 0 && s.stage.rfind("mls_", 0) != 0 && s.stage != "coupling_exchange") ms += s.ms;
  return ms;
}

// --pbd-iterations / --chebyshev-rho: the PBD iterations per substep and, for Jacobi, the Chebyshev estimate.
int g_pbd_iterations = 10;
double g_chebyshev_rho = 0;
// --end-frames: cutting.stroke_end_frames (the stroke's end computed by a worker, applied that many frames later);
// --pace-hz: frames start at this rate (an interactive loop; the worker gets the idle time), 0: back to back.
int g_end_frames = 0;
double g_pace_hz = 0;
double g_blade_radius = 0;  // --blade-radius: cutting.blade_radius_m (the blade as a contact)
int g_conversion_delay =
    0;                  // --conversion-delay: cutting.conversion_delay_frames (conversions prepared beside a frame)
int g_open_frames = 0;  // --open-frames: cutting.open_surface_frames (the surface opened during the stroke)

struct Row {
  std::string kind, backend, solver;
  int pbd_iterations = 0;
  int target = 0, spheres = 0, nodal_points = 0, interface = 0, spheres_after = 0, mls_substeps = 0;
  double cut_length_m = 0;
  double ms_deform = 0, ms_cutting = 0, ms_mls = 0, ms_exchange = 0, ms_pbd = 0, ms_convert = 0;
  double ms_repack = 0, ms_apply_frame = 0, ms_after = 0;
  // The stroke's end: the frame the blade leaves, the frames until the end is applied, the applying frame's wait
  // for the worker, and the worker's parts (the same frame as apply when --end-frames is 0).
  double ms_end_frame = 0, ms_ending = 0, ms_apply_wait = 0;
  double ms_end_worker = 0, ms_end_split = 0, ms_end_repack = 0, ms_end_build = 0, ms_end_bind = 0;
};

// The liver_cut organ (ellipsoid 18 x 12 x 7 cm, bed glued) at the lattice spacing that gives about `target`
// spheres; a straight scalpel (10 cm vertical blade) along x in the plane y = 4 mm from x = -12 cm over
// `length_m` between 0.1 s and 0.4 s, then held in the tissue until `leave_s`.
Scene liverScene(int target, double length_m, double leave_s, int samples, const std::string& pbd_solver) {
  Scene s;
  s.file = "<bench:cutting>";
  s.geometry.kind = GeometrySpec::Kind::Ellipsoid;
  s.geometry.radii = Vec3d(0.09, 0.06, 0.035);
  const double volume = 4.0 / 3.0 * 3.141592653589793 * 0.09 * 0.06 * 0.035;
  s.geometry.spacing = std::cbrt(volume / target);
  s.material.youngs_modulus_pa = 5e3;
  s.material.damping_per_s = 4.0;
  s.models.pbd_metaballs = true;
  s.models.cutting = true;
  s.solver.substeps = 4;
  s.pbd.iterations = g_pbd_iterations;
  s.pbd.solver = pbd_solver;
  s.pbd.chebyshev_rho = pbd_solver == "jacobi" ? g_chebyshev_rho : 0.0;  // the acceleration is Jacobi's
  s.cutting.samples_per_diameter = samples;
  s.cutting.stroke_end_frames = g_end_frames;
  s.cutting.blade_radius_m = g_blade_radius;
  s.cutting.conversion_delay_frames = g_conversion_delay;
  s.cutting.open_surface_frames = g_open_frames;
  s.fixed = {{Vec3d(-0.1, -0.07, -0.04), Vec3d(0.1, 0.07, -0.02)}};
  ToolSpec t;
  t.name = "scalpel";
  t.kind = "scalpel";
  t.length = 0.1;
  const double x1 = -0.12 + length_m;
  t.path = {{0.1, Vec3d(-0.12, 0.004, 0), Vec3d(0, 0, 1)},
            {0.4, Vec3d(x1, 0.004, 0), Vec3d(0, 0, 1)},
            {leave_s, Vec3d(x1, 0.004, 0), Vec3d(0, 0, 1)}};
  s.tools = {t};
  return s;
}

// The PBD solver of a backend: Gauss-Seidel on the CPU; Jacobi on the GPU, where a liver-sized model's ~80 colours
// make Gauss-Seidel ~80 dependent phases per iteration (docs/pbd.md, "Solvers").
std::string solverFor(const std::string& choice, BackendKind backend) {
  if (choice != "auto") return choice;
  return backend == BackendKind::Cuda ? "jacobi" : "gauss_seidel";
}

// Median ms of every stage over the cutting frames, printed with --stages.
void printStages(const std::string& label, const std::map<std::string, std::vector<double>>& stages) {
  std::printf("  stages of the cutting frames (%s), median ms:", label.c_str());
  for (const auto& [name, v] : stages) {
    if (median(v) >= 0.005) std::printf(" %s %.3f", name.c_str(), median(v));
  }
  std::printf("\n");
}

// Frames: deforming (before the blade), cutting (the points exist), the frame that re-packs, after.
Row runCase(const std::string& kind, BackendKind backend, int target, double length_m, int samples, int after_frames,
            const std::string& pbd_solver, bool stages) {
  Row r;
  r.kind = kind;
  r.backend = backendName(backend);
  r.target = target;
  r.cut_length_m = length_m;
  const double leave = 0.5;
  r.solver = solverFor(pbd_solver, backend);
  const Scene scene = liverScene(target, length_m, leave, samples, r.solver);
  r.pbd_iterations = scene.pbd.iterations;
  if (scene.pbd.chebyshev_rho > 0) {
    char label[32];
    std::snprintf(label, sizeof label, "jacobi_ch%.2f", scene.pbd.chebyshev_rho);
    r.solver = label;
  }
  std::map<std::string, std::vector<double>> stage_ms;
  auto sim = makeDissectionSimulation(compileScene(scene), backend, Precision::Float32);
  r.spheres = int(sim->particleCount());
  std::vector<double> deform, cutting, mls, exchange, pbd, convert, after, ending;
  const double dt = 1.0 / 60.0;
  bool applied = false, ended = false;
  for (int f = 0; f < 200; ++f) {
    const auto c0 = Clock::now();
    const FrameReport rep = sim->advance(dt);
    const double ms = msSince(c0);
    if (g_pace_hz > 0) std::this_thread::sleep_until(c0 + std::chrono::duration<double>(1.0 / g_pace_hz));
    if (!rep.finite) throw InputError("bench_cutting", "frame", "non-finite state at frame " + std::to_string(f));
    const double points = rep.counters.at("nodal_points");
    const bool pending = rep.counters.at("stroke_end_pending") > 0;
    if (pending && !ended) {
      ended = true;
      r.ms_end_frame = ms;
    } else if (pending) {
      ending.push_back(ms);
    } else if (rep.counters.at("cuts_applied") > 0 && !applied) {
      applied = true;
      if (!ended) r.ms_end_frame = ms;  // applied in the frame the blade left
      r.ms_apply_frame = ms;
      r.ms_apply_wait = stage(rep, "cut_apply_wait");
      r.ms_repack = stage(rep, "cut_repack");
      r.ms_end_worker = rep.counters.at("stroke_end_worker_ms");
      r.ms_end_split = rep.counters.at("stroke_end_split_ms");
      r.ms_end_repack = rep.counters.at("stroke_end_repack_ms");
      r.ms_end_build = rep.counters.at("stroke_end_build_ms");
      r.ms_end_bind = rep.counters.at("stroke_end_bind_ms");
      r.spheres_after = int(rep.counters.at("spheres"));
    } else if (applied) {
      after.push_back(ms);
      if (int(after.size()) >= after_frames) break;
    } else if (points > 0) {
      cutting.push_back(ms);
      mls.push_back(stage(rep, "mls_wall"));  // the stages' GPU times overlap the wall time: not summed
      exchange.push_back(stage(rep, "coupling_exchange"));
      pbd.push_back(pbdStages(rep));
      convert.push_back(stage(rep, "cut_convert"));
      std::map<std::string, double> frame_stages;  // a stage may be reported once per exchange
      for (const auto& st : rep.stages) frame_stages[st.stage] += st.ms;
      for (const auto& [name, ms_stage] : frame_stages) stage_ms[name].push_back(ms_stage);
      if (int(points) >= r.nodal_points) {
        r.nodal_points = int(points);
        r.interface = int(rep.counters.at("interface_spheres"));
        r.mls_substeps = int(rep.counters.at("mls_substeps"));
      }
    } else {
      deform.push_back(ms);
    }
  }
  r.ms_deform = median(deform);
  r.ms_cutting = median(cutting);
  r.ms_mls = median(mls);
  r.ms_exchange = median(exchange);
  r.ms_pbd = median(pbd);
  r.ms_convert = median(convert);
  r.ms_after = median(after);
  r.ms_ending = median(ending);
  if (stages) printStages(r.backend + " " + r.solver, stage_ms);
  return r;
}

void printRow(const Row& r) {
  std::printf(
      "%-6s %-5s %-12s %7d %7d %6.3f %7d %6d %5d | %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f | %8.2f %8.2f %8.2f %7d"
      " | %8.2f %8.2f %8.2f %8.2f\n",
      r.kind.c_str(), r.backend.c_str(), r.solver.c_str(), r.target, r.spheres, r.cut_length_m, r.nodal_points,
      r.interface, r.mls_substeps, r.ms_deform, r.ms_cutting, r.ms_mls, r.ms_exchange, r.ms_pbd, r.ms_convert,
      r.ms_repack, r.ms_apply_frame, r.ms_after, r.spheres_after, r.ms_end_frame, r.ms_ending, r.ms_apply_wait,
      r.ms_end_worker);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Cutting: frame time with the MLS nodal points coupled, the re-packing, frame time vs cut length"};
  std::string backend_text = "auto", csv, sizes_text = "500,2000,8000", lengths_text = "0.06,0.12,0.18,0.24";
  int max_spheres = 32000, cpu_max = 8000, samples = 3, long_target = 500, after_frames = 6;
  bool quick = false, portable = false, stages = false;
  std::string pbd_solver = "auto";
  app.add_option("--backend", backend_text, "cpu | cuda | auto | both");
  app.add_option("--sizes", sizes_text, "target sphere counts of the full-length cut, comma separated");
  app.add_option("--lengths", lengths_text, "cut lengths (m) of the long-cut series, comma separated");
  app.add_option("--long-target", long_target, "sphere count of the long-cut series");
  app.add_option("--samples", samples, "cutting.samples_per_diameter");
  app.add_option("--max", max_spheres, "skip sizes above this many spheres");
  app.add_option("--cpu-max", cpu_max, "skip CPU rows above this many spheres");
  app.add_option("--csv", csv, "write the rows as CSV here");
  app.add_option("--pbd-solver", pbd_solver, "auto (Gauss-Seidel on the CPU, Jacobi on CUDA) | jacobi | gauss_seidel")
      ->check(CLI::IsMember({"auto", "jacobi", "gauss_seidel"}));
  app.add_option("--pbd-iterations", g_pbd_iterations, "PBD iterations per substep (the scene's pbd.iterations)");
  app.add_option("--chebyshev-rho", g_chebyshev_rho,
                 "Jacobi PBD: Chebyshev acceleration with this spectral-radius estimate, [0, 0.9] (pbd.chebyshev_rho)");
  app.add_option("--end-frames", g_end_frames, "cutting.stroke_end_frames: apply a stroke's end this many frames later")
      ->check(CLI::Range(0, 120));
  app.add_option("--blade-radius", g_blade_radius, "cutting.blade_radius_m: the blade's contact capsule (m), 0: none")
      ->check(CLI::Range(0.0, 0.05));
  app.add_option(
         "--conversion-delay", g_conversion_delay,
         "cutting.conversion_delay_frames: 1 prepares each conversion beside the frame and applies it at the next")
      ->check(CLI::Range(0, 1));
  app.add_option("--open-frames", g_open_frames,
                 "cutting.open_surface_frames: open the surface along the sweep so far on a worker, shown this many "
                 "frames later")
      ->check(CLI::Range(0, 120));
  app.add_option("--pace-hz", g_pace_hz, "start frames at this rate (an interactive loop); 0: back to back")
      ->check(CLI::Range(0.0, 10000.0));
  app.add_flag("--stages", stages, "print the median of every stage of the cutting frames");
  app.add_flag("--quick", quick, "a short run: size 500, lengths 0.06,0.24");
  app.add_flag("--portable-pair-sums", portable,
               "CPU MLS: the portable pair loops even where the CPU has AVX2 (same bits)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    inc::cpu::setMlsPairSumsPortable(portable);
    if (quick) {
      sizes_text = "500";
      lengths_text = "0.06,0.24";
      after_frames = 3;
    }
    const auto parse = [](const std::string& text) {
      std::vector<double> v;
      for (std::size_t a = 0; a < text.size();) {
        const std::size_t b = std::min(text.find(',', a), text.size());
        v.push_back(std::stod(text.substr(a, b - a)));
        a = b + 1;
      }
      return v;
    };
    const std::vector<double> sizes = parse(sizes_text), lengths = parse(lengths_text);
    std::vector<BackendKind> backends;
    if (backend_text == "both") {
      backends = {BackendKind::Cpu, BackendKind::Cuda};
    } else {
      backends = {resolveBackend(parseBackend(backend_text)).kind};
    }
    bool have_gpu = false;
#if INCISION_HAVE_CUDA
    have_gpu = inc::cuda::queryDevices().device_count > 0;
#endif
    std::vector<Row> rows;
    std::printf(
        "%-6s %-5s %-12s %7s %7s %6s %7s %6s %5s | %8s %8s %8s %8s %8s %8s | %8s %8s %8s %7s | %8s %8s %8s %8s\n",
        "case", "back", "pbd", "target", "spheres", "len_m", "nodes", "iface", "mlsub", "deform", "cutting", "mls",
        "exchng", "pbd", "convert", "repack", "apply", "after", "spheres", "end", "ending", "wait", "worker");
    for (BackendKind b : backends) {
      if (b == BackendKind::Cuda && !have_gpu) continue;
      for (double n : sizes) {
        if (n > max_spheres || (b == BackendKind::Cpu && n > cpu_max)) continue;
        rows.push_back(runCase("size", b, int(n), 0.24, samples, after_frames, pbd_solver, stages));
        printRow(rows.back());
      }
      for (double len : lengths) {
        rows.push_back(runCase("length", b, long_target, len, samples, after_frames, pbd_solver, stages));
        printRow(rows.back());
      }
    }
    if (!csv.empty()) {
      std::ofstream f(csv);
      if (!f) throw InputError(csv, "--csv", "cannot write");
      f << "case,backend,target,spheres,cut_length_m,nodal_points,interface_spheres,mls_substeps,ms_deform,ms_cutting,"
           "ms_mls,ms_exchange,ms_pbd,ms_convert,ms_repack,ms_apply_frame,ms_after,spheres_after,pbd_solver,pbd_"
           "iterations,"
           "stroke_end_frames,pace_hz,ms_end_frame,ms_ending,ms_apply_wait,ms_end_worker,ms_end_split,ms_end_repack,"
           "ms_end_build,ms_end_bind,blade_radius_m,conversion_delay_frames,open_surface_frames\n";
      for (const Row& r : rows)
        f << r.kind << ',' << r.backend << ',' << r.target << ',' << r.spheres << ',' << r.cut_length_m << ','
          << r.nodal_points << ',' << r.interface << ',' << r.mls_substeps << ',' << r.ms_deform << ',' << r.ms_cutting
          << ',' << r.ms_mls << ',' << r.ms_exchange << ',' << r.ms_pbd << ',' << r.ms_convert << ',' << r.ms_repack
          << ',' << r.ms_apply_frame << ',' << r.ms_after << ',' << r.spheres_after << ',' << r.solver << ','
          << r.pbd_iterations << ',' << g_end_frames << ',' << g_pace_hz << ',' << r.ms_end_frame << ',' << r.ms_ending
          << ',' << r.ms_apply_wait << ',' << r.ms_end_worker << ',' << r.ms_end_split << ',' << r.ms_end_repack << ','
          << r.ms_end_build << ',' << r.ms_end_bind << ',' << g_blade_radius << ',' << g_conversion_delay << ','
          << g_open_frames << '\n';
    }
    if (rows.empty()) {
      std::printf("bench_cutting: no rows (sizes above the limits or no device)\n");
      return 0;
    }
    const Row& first = rows.front();
    std::printf(
        "bench_cutting: %s (%s PBD) %d spheres, conversion delay %d: %.3f ms per frame while cutting (%d nodal "
        "points), re-packing %.3f ms; "
        "stroke end (%d frames late): blade-leaving frame %.2f ms, applying frame %.2f ms (waited %.2f), workers %.2f "
        "ms\n",
        first.backend.c_str(), first.solver.c_str(), first.spheres, g_conversion_delay, first.ms_cutting,
        first.nodal_points, first.ms_repack, g_end_frames, first.ms_end_frame, first.ms_apply_frame,
        first.ms_apply_wait, first.ms_end_worker);
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
