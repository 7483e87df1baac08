// MLS elasticity step time per stage against particle count (CPU and CUDA, float32/float64), bandwidth, accuracy.
#include <CLI/CLI.hpp>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench_memory.h"
#include "bench/mls_traffic.h"
#include "cpu_fallback/mls_solver_cpu.h"
#include "host/assembly/mls_model_build.h"
#include "host/assembly/particle_sampling.h"
#include "host/backends/backend_choice.h"
#include "host/backends/solver_factory.h"
#include "kernels/device_info.h"
#include "model/backend.h"
#include "model/input_error.h"
#include "model/mls_model.h"
#include "model/mls_solver.h"
#if INCISION_HAVE_CUDA
#include "kernels/mls_solver_cuda.h"
#endif

using namespace inc;

namespace {

struct Row {
  std::string backend, precision;
  std::int64_t particles = 0;
  double mean_neighbors = 0;
  double ms_step = 0, ms_integrate = 0, ms_stress = 0, ms_forces = 0;  // medians per substep
  double ms_wall = 0;  // wall time per substep seen by the host (GPU: includes launch gaps and event calls)
  double particles_per_s = 0;
  double mbytes_per_step = 0, gbytes_per_s = 0;
  double ms_step_min = 0, ms_step_max = 0;        // spread of the timed repeats
  double host_peak_mib = 0, device_peak_mib = 0;  // bench/bench_memory.h: the row's peaks
};

// A cube of about n lattice particles (spacing 5 mm, support 2 spacings: 32 neighbours inside), jittered,
// clamped at x = min, gravity on, so every stage does its full work.
MlsBuildInput cubeInput(std::int64_t n) {
  const double s = 0.005;
  const int side = std::max(2, int(std::lround(std::cbrt(double(n)))));
  MlsBuildInput in;
  in.rest_positions = sampleBox(Vec3d(0, 0, 0), Vec3d(side * s, side * s, side * s), LatticeSpec{s, 0.1, 3});
  in.spacing = s;
  in.material.youngs_modulus_pa = 1e4;
  in.material.poisson_ratio = 0.45;
  in.material.density_kg_m3 = 1000;
  in.material.damping_per_s = 1.0;
  in.kinds.resize(in.rest_positions.size());
  const double x0 = -0.5 * side * s + s;
  for (std::size_t i = 0; i < in.kinds.size(); ++i) in.kinds[i] = in.rest_positions[i].x < x0 ? kMlsFixed : kMlsFree;
  in.source = "<bench cube>";
  return in;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

Row timeSolver(MlsSolver& solver, int substeps, int repeats) {
  Row r;
  r.backend = backendName(solver.backend());
  r.precision = precisionName(solver.precision());
  r.particles = std::int64_t(solver.size());
  r.mean_neighbors = solver.modelStats().mean_neighbors;
  const double dt = 0.5 * solver.stableTimeStep();
  solver.advance(dt * substeps, substeps);  // warm-up (first-touch, kernel load)
  std::vector<double> step, integ, stress, forces, walls;
  for (int k = 0; k < repeats; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    const MlsFrameStats st = solver.advance(dt * substeps, substeps);
    const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    walls.push_back((wall - st.ms_reduce) / substeps);
    integ.push_back(st.ms_integrate / substeps);
    stress.push_back(st.ms_stress / substeps);
    forces.push_back(st.ms_forces / substeps);
    // GPU: sum of the stage events (device time); CPU: wall time of the frame less the reduction.
    step.push_back(solver.backend() == BackendKind::Cuda ? (st.ms_integrate + st.ms_stress + st.ms_forces) / substeps
                                                         : (wall - st.ms_reduce) / substeps);
  }
  r.ms_step = median(step);
  r.ms_step_min = *std::min_element(step.begin(), step.end());
  r.ms_step_max = *std::max_element(step.begin(), step.end());
  r.ms_wall = median(walls);
  r.ms_integrate = median(integ);
  r.ms_stress = median(stress);
  r.ms_forces = median(forces);
  r.particles_per_s = double(r.particles) / (r.ms_step * 1e-3);
  const std::size_t t = solver.precision() == Precision::Float64 ? 8 : 4;
  const double bytes = bench::mlsStepBytes(r.particles, r.mean_neighbors * double(r.particles), t);
  r.mbytes_per_step = bytes / 1e6;
  r.gbytes_per_s = bytes / (r.ms_step * 1e-3) / 1e9;
  return r;
}

void printRow(const Row& r) {
  std::printf("%-5s %-8s %10lld %6.1f %11.4f %10.4f %10.4f %10.4f %10.4f %12.3e %9.2f %8.1f\n", r.backend.c_str(),
              r.precision.c_str(), (long long)r.particles, r.mean_neighbors, r.ms_step, r.ms_wall, r.ms_integrate,
              r.ms_stress, r.ms_forces, r.particles_per_s, r.mbytes_per_step, r.gbytes_per_s);
  std::fflush(stdout);
}

// float32 against float64 on the same model and motion: relative displacement error after `steps` steps.
double precisionError(BackendKind backend, std::int64_t n, int steps, double& ms32, double& ms64) {
  const MlsBuildInput in = cubeInput(n);
  auto s64 = makeMlsSolver(in, backend, Precision::Float64);
  auto s32 = makeMlsSolver(in, backend, Precision::Float32);
  const double dt = 0.5 * std::min(s64->stableTimeStep(), s32->stableTimeStep());
  s64->step(dt, 1);
  s32->step(dt, 1);
  auto t0 = std::chrono::steady_clock::now();
  s64->step(dt, steps);
  ms64 = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / steps;
  t0 = std::chrono::steady_clock::now();
  s32->step(dt, steps);
  ms32 = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / steps;
  std::vector<Vec3d> a, b;
  s64->displacements(a);
  s32->displacements(b);
  double diff = 0, mag = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    diff = std::max(diff, norm(a[i] - b[i]));
    mag = std::max(mag, norm(a[i]));
  }
  return mag > 0 ? diff / mag : 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"MLS elasticity: time per substep (drift + stress pass + force pass) against particle count"};
  std::string backend_text = "auto", precision_text = "both", csv;
  std::int64_t lo = 1000, hi = 16000000, cpu_max = 1000000;
  int substeps = 20, repeats = 5, cpu_threads = 0;
  bool quick = false;
  app.add_option("--backend", backend_text, "cpu | cuda | auto (auto: CUDA when usable, plus the CPU up to --cpu-max)");
  app.add_option("--precision", precision_text, "float32 | float64 | both")
      ->check(CLI::IsMember({"float32", "float64", "both"}));
  app.add_option("--min", lo, "smallest particle count");
  app.add_option("--max", hi, "largest particle count on the GPU");
  app.add_option("--cpu-max", cpu_max, "largest particle count on the CPU (0: no CPU rows)");
  app.add_option("--substeps", substeps, "substeps per timed frame");
  app.add_option("--repeats", repeats, "timed frames per size after one warm-up frame (median reported)");
  app.add_option("--cpu-threads", cpu_threads, "OpenMP threads for the CPU rows (0: default)");
  app.add_option("--csv", csv, "write the rows as CSV here");
  app.add_flag("--quick", quick, "a short run: sizes up to 1e5 (GPU) / 3e4 (CPU), 3 repeats of 10 substeps");
  CLI11_PARSE(app, argc, argv);

  try {
    if (lo < 8 || hi < lo || substeps < 1 || repeats < 1)
      throw InputError("", "--min/--max/--substeps/--repeats", "out of range");
    if (cpu_threads > 0) omp_set_num_threads(cpu_threads);
    if (quick) {
      hi = std::min<std::int64_t>(hi, 100000);
      cpu_max = std::min<std::int64_t>(cpu_max, 30000);
      substeps = std::min(substeps, 10);
      repeats = std::min(repeats, 3);
    }
    const BackendKind requested = parseBackend(backend_text);
    bool gpu = false;
    std::string note;
#if INCISION_HAVE_CUDA
    if (requested != BackendKind::Cpu) {
      const BackendChoice c = resolveBackend(requested);
      gpu = c.kind == BackendKind::Cuda;
      note = c.note;
    }
#else
    if (requested == BackendKind::Cuda) throw InputError("", "--backend", "this build has no CUDA backend");
    note = "CPU only (built without CUDA)";
#endif
    const bool cpu = requested == BackendKind::Cpu || (cpu_max >= lo && requested == BackendKind::Auto) || !gpu;
    if (requested == BackendKind::Cpu) cpu_max = std::max(cpu_max, hi);
    std::vector<Precision> precs;
    if (precision_text != "float64") precs.push_back(Precision::Float32);
    if (precision_text != "float32") precs.push_back(Precision::Float64);

    std::printf(
        "# bench_mls: %s; CPU threads %d; %d substeps x %d repeats (median); cube of lattice particles, "
        "support 2 spacings\n",
        note.empty() ? "-" : note.c_str(), omp_get_max_threads(), substeps, repeats);
    std::printf("%-5s %-8s %10s %6s %11s %10s %10s %10s %10s %12s %9s %8s\n", "back", "prec", "particles", "nbrs",
                "ms/step", "wall ms", "integrate", "stress", "forces", "particles/s", "MB/step", "GB/s");
    std::vector<Row> rows;
    std::vector<std::int64_t> sizes;
    for (double n = double(lo); n <= double(hi) * 1.0001; n *= 4) sizes.push_back(std::int64_t(n));
    if (sizes.back() != hi) sizes.push_back(hi);
    for (const std::int64_t n : sizes) {
      const bool run_gpu = gpu, run_cpu = cpu && n <= cpu_max;
      if (!run_gpu && !run_cpu) continue;
      for (const Precision p : precs) {
        const MlsBuildInput in = cubeInput(n);
        auto runBoth = [&](auto model) {
          // The row's peak host memory (the model is already resident) and the device memory its solver holds.
          auto timed = [&](MlsSolver& solver, bench::HostPeak& host, double dev0) {
            rows.push_back(timeSolver(solver, substeps, repeats));
            rows.back().host_peak_mib = host.mib();
            rows.back().device_peak_mib = bench::deviceUsedMiB(solver.backend()) - dev0;
            printRow(rows.back());
          };
          if (run_cpu) {
            bench::HostPeak host;
            host.reset();
            auto solver = cpu::makeMlsSolverCpu(run_gpu ? decltype(model)(model) : std::move(model));
            timed(*solver, host, 0.0);
          }
#if INCISION_HAVE_CUDA
          if (run_gpu) {
            bench::HostPeak host;
            host.reset();
            const double dev0 = bench::deviceUsedMiB(BackendKind::Cuda);
            auto solver = cuda::makeMlsSolverCuda(std::move(model));
            timed(*solver, host, dev0);
          }
#endif
        };
        if (p == Precision::Float64)
          runBoth(buildMlsModel<double>(in));
        else
          runBoth(buildMlsModel<float>(in));
      }
    }

    // Accuracy against speed: float32 vs float64 on the same 1e4-particle cube after 500 substeps.
    const BackendKind acc_backend = gpu ? BackendKind::Cuda : BackendKind::Cpu;
    double ms32 = 0, ms64 = 0;
    const int acc_steps = quick ? 100 : 500;
    const double err = precisionError(acc_backend, 10000, acc_steps, ms32, ms64);
    std::printf(
        "# accuracy (%s, 1e4 particles, %d substeps): float32 vs float64 max |du| / max |u| = %.3e; "
        "%.4f ms/step float32, %.4f ms/step float64 (%.2fx)\n",
        backendName(acc_backend), acc_steps, err, ms32, ms64, ms64 / ms32);

    if (!csv.empty()) {
      std::ofstream f(csv);
      if (!f) throw InputError(csv, "--csv", "cannot write the file");
      // kind "timing": one row per backend, precision and size; kind "accuracy": the float32 and float64 runs of
      // the same 1e4-particle motion (wall ms per step, float32's max |du| / max |u| against float64).
      f << "kind,backend,precision,particles,mean_neighbors,ms_per_step,wall_ms_per_step,ms_integrate,ms_stress,"
           "ms_forces,particles_per_s,mbytes_per_step,gbytes_per_s,rel_error_vs_float64,ms_per_step_min,ms_per_step_"
           "max,"
           "host_peak_mib,device_peak_mib\n";
      for (const Row& r : rows)
        f << "timing," << r.backend << ',' << r.precision << ',' << r.particles << ',' << r.mean_neighbors << ','
          << r.ms_step << ',' << r.ms_wall << ',' << r.ms_integrate << ',' << r.ms_stress << ',' << r.ms_forces << ','
          << r.particles_per_s << ',' << r.mbytes_per_step << ',' << r.gbytes_per_s << ",," << r.ms_step_min << ','
          << r.ms_step_max << ',' << r.host_peak_mib << ',' << r.device_peak_mib << '\n';
      f << "accuracy," << backendName(acc_backend) << ",float32,10000,," << ms32 << ',' << ms32 << ",,,,,,," << err
        << ",,,,\n";
      f << "accuracy," << backendName(acc_backend) << ",float64,10000,," << ms64 << ',' << ms64 << ",,,,,,,0,,,,\n";
    }
    // Summary line (last line of stdout): the largest float32 row of the fastest backend.
    const Row* best = nullptr;
    for (const Row& r : rows)
      if (r.precision == "float32" &&
          (!best || r.particles > best->particles || (r.particles == best->particles && r.ms_step < best->ms_step)))
        best = &r;
    // Achieved bandwidth against the device's measured peak (a device-to-device copy, read + write).
    const double peak = best && best->backend == "cuda" ? cuda::measureCopyBandwidthGbs() : 0.0;
    char frac[64] = "";
    if (peak > 0)
      std::snprintf(frac, sizeof frac, ", %.0f %% of the measured %.0f GB/s", 100.0 * best->gbytes_per_s / peak, peak);
    if (best)
      std::printf(
          "bench_mls: %s float32 %lld particles %.4f ms/step (%.3e particles/s, %.1f GB/s%s); f32-vs-f64 rel err "
          "%.2e\n",
          best->backend.c_str(), (long long)best->particles, best->ms_step, best->particles_per_s, best->gbytes_per_s,
          frac, err);
    else
      std::printf("bench_mls: no float32 row; f32-vs-f64 rel err %.2e\n", err);
  } catch (const InputError& e) {
    std::fprintf(stderr, "bench_mls: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_mls: %s\n", e.what());
    return 1;
  }
  return 0;
}
