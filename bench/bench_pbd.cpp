// PBD/XPBD metaball solver: frame time and constraints/s against sphere count (CPU and CUDA, Jacobi and Gauss-Seidel),
// and residual/deflection against iterations.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench_memory.h"
#include "host/assembly/pbd_builders.h"
#include "host/backends/solver_factory.h"
#include "model/backend.h"
#include "model/input_error.h"
#include "model/pbd_model.h"
#if INCISION_HAVE_CUDA
#include "kernels/device_info.h"
#endif

using namespace inc;

namespace {

struct Row {
  std::string table, backend, precision, solver, path = "-";  // path (CUDA): cluster | grid | fused | launches
  std::int64_t spheres = 0, constraints = 0;
  int iterations = 0, substeps = 0, colors = 0;
  std::string stages;  // "name=ms ..." of the last timed frame
  double ms_frame = 0, constraints_per_s = 0, residual_max = 0, residual_rms = 0, deflection_m = 0, deflection_err = 0;
  double ms_min = 0, ms_max = 0;                  // spread of the timed frames
  double mbytes_frame = 0, gbytes_per_s = 0;      // compulsory traffic of a frame (frameBytes) and its rate
  double host_peak_mib = 0, device_peak_mib = 0;  // bench/bench_memory.h: the row's peaks
};

const double kSpacing = 0.005;  // m

// A clamped block of about n metaballs (4:1:1, 5 mm lattice, radius 0.75 spacing, E = 5 kPa): shape
// matching, Laplacian and stretch constraints, volume preservation near the probe that presses its middle.
template <typename T>
PbdModel<T> blockModel(std::int64_t n, Vec3d& size) {
  const int ny = std::max(1, int(std::lround(std::cbrt(double(n) / 4.0))));
  const int nx = std::max(2, int(std::lround(double(n) / (ny * ny))));
  size = Vec3d((nx - 1) * kSpacing, (ny - 1) * kSpacing, (ny - 1) * kSpacing);
  const MetaballModel mb = makeLatticeMetaballs(Vec3d(0, 0, 0), size, kSpacing, 0.75, 1060.0);
  MetaballPbdOptions opt;
  opt.youngs_modulus_pa = 5.0e3;
  opt.volume_samples = 32;
  FixedRegion r;
  r.min = Vec3d(-1, -1, -1);
  r.max = Vec3d(0.5 * kSpacing, 1, 1);
  opt.fixed.push_back(r);
  return buildMetaballPbdModel<T>(mb, opt);
}

template <typename T>
PbdFrameInput<T> probeInput(const Vec3d& size) {
  PbdFrameInput<T> in;
  pbd::CapsuleCollider<T> c;
  c.a = Vec3<T>(T(0.5 * size.x), T(-0.01), T(size.z + 0.5 * kSpacing));
  c.b = Vec3<T>(T(0.5 * size.x), T(size.y + 0.01), T(size.z + 0.5 * kSpacing));
  c.radius = T(0.004);
  in.tools_from.push_back(c);
  in.tools_to.push_back(c);
  return in;
}

std::int64_t solvedConstraints(const PbdModel<float>& m) {
  std::int64_t c = 0;
  for (const auto& b : m.blocks)
    if (b.solve) c += std::int64_t(b.count());
  return c;
}
std::int64_t solvedConstraints(const PbdModel<double>& m) {
  std::int64_t c = 0;
  for (const auto& b : m.blocks)
    if (b.solve) c += std::int64_t(b.count());
  return c;
}

// Compulsory traffic of one frame (bytes), a lower bound that counts every array a phase streams once (neighbour
// reads inside a phase assumed to hit the caches): per iteration and solved block, the projection reads the
// constraint offsets, slot ids, rest data, compliances and Jacobi scales, reads and writes the multipliers and
// reads the positions (plus inverse masses, and masses for shape matching) once; Jacobi writes the slot
// corrections and its gather reads the particle -> slot CSR and the corrections and reads and writes the
// positions; Gauss-Seidel writes the positions in place instead. Per iteration the contacts read and write the
// positions (and read radii and inverse masses); per substep the prediction reads and writes positions and
// velocities and writes the previous positions, the velocity update reads both position arrays and writes
// velocities. The once-per-frame radius solve is left out.
template <typename T>
double frameBytes(const PbdModel<T>& m, int iterations, int substeps, bool jacobi) {
  const double n = double(m.size()), v3 = double(sizeof(Vec3<T>)), t = double(sizeof(T)), i4 = 4.0;
  double iter = 0;
  for (const PbdConstraintBlock<T>& b : m.blocks) {
    if (!b.solve || b.count() == 0) continue;
    const double c = double(b.count()), sl = double(b.slotCount());
    const double mult = double(b.multiplierCount()) * (b.vectorMultiplier() ? v3 : t);
    double proj = i4 * (c + 1) + i4 * sl + double(b.rest.size()) * t + double(b.rest_vec.size()) * v3 +
                  double(b.compliance.size()) * t + 2 * mult + n * (v3 + t);
    if (b.kind == PbdConstraintKind::ShapeMatching) proj += n * t;  // masses (centre of mass)
    if (jacobi)
      proj += double(b.jacobi_scale.size()) * t + sl * v3 +   // scales, slot corrections written
              i4 * (n + 1) + i4 * sl + sl * v3 + 2 * n * v3;  // gather
    else
      proj += n * v3;  // positions written in place
    iter += proj;
  }
  iter += 2 * n * v3 + 2 * n * t;                      // contacts
  const double sub = 4 * n * v3 + n * t + 3 * n * v3;  // predict (x, v read+write, x_prev written, w), velocities
  return double(substeps) * (double(iterations) * iter + sub);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Time bounds of the whole run: each timed point stops after g_row_seconds of wall time (at least 3 timed
// frames), and points that would start after g_deadline are skipped (counted in g_skipped).
double g_row_seconds = 2.0;
bool g_profile = false;
double g_jacobi_omega = PbdStepParams<double>{}.jacobi_omega;
int g_rotation_iterations = PbdStepParams<double>{}.rotation_iterations;
bool g_no_graph = false;  // --no-graph
std::chrono::steady_clock::time_point g_deadline = std::chrono::steady_clock::time_point::max();
int g_skipped = 0;
bool pastDeadline() { return std::chrono::steady_clock::now() > g_deadline; }

// A solver as the tables name it: Jacobi with Chebyshev acceleration (rho > 0) is its own row.
struct Solve {
  PbdSolverKind kind = PbdSolverKind::Jacobi;
  double rho = 0;  // PbdStepParams::chebyshev_rho
  std::string name() const {
    if (kind == PbdSolverKind::GaussSeidel) return "gauss_seidel";
    if (!(rho > 0)) return "jacobi";
    char buf[32];
    std::snprintf(buf, sizeof buf, "jacobi_ch%.2f", rho);
    return buf;
  }
};

// Frame time: CUDA events (the backend's "frame" stage) on the GPU, wall clock on the CPU; median of up to
// `repeats` frames (fewer when a point's time budget runs out) after up to 3 warm-up frames (graph capture,
// first touch). --profile: one more frame with per-stage CUDA events (no graph, no fusion) gives the stage split.
template <typename T>
Row timeFrames(BackendKind kind, Solve solver, std::int64_t n, int iterations, int substeps, int repeats,
               int fused_max = 4096, int cluster_max = PbdStepParams<float>{}.cluster_max_particles,
               int grid_max = PbdStepParams<float>{}.grid_max_particles) {
  bench::HostPeak host;
  host.reset();
  const double dev0 = bench::deviceUsedMiB(kind);
  Vec3d size;
  const PbdModel<T> m = blockModel<T>(n, size);
  auto be = makePbdBackend<T>(kind);
  be->setModel(m);
  PbdStepParams<T> p;
  p.solver = solver.kind;
  p.chebyshev_rho = T(solver.rho);
  p.jacobi_omega = T(g_jacobi_omega);
  p.rotation_iterations = g_rotation_iterations;
  p.iterations = iterations;
  p.substeps = substeps;
  p.volume_influence = T(2 * kSpacing);
  p.fused_max_particles = fused_max;
  p.cluster_max_particles = cluster_max;
  p.grid_max_particles = grid_max;
  p.use_graph = !g_no_graph;
  const PbdFrameInput<T> in = probeInput<T>(size);
  PbdFrameStats st;
  const auto row_start = std::chrono::steady_clock::now();
  const auto spent = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - row_start).count();
  };
  for (int k = 0; k < 3 && (k == 0 || spent() < 0.25 * g_row_seconds); ++k) st = be->advanceFrame(p, in);
  std::vector<double> ms;
  int team_frames = 0;  // CPU: timed frames that ran on a team of threads from start to end
  for (int k = 0; k < repeats && (k < 3 || spent() < g_row_seconds); ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    st = be->advanceFrame(p, in);
    team_frames += st.threads > 1 && !st.team_stalled ? 1 : 0;
    const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    double ev = -1;
    for (const auto& s : st.stages)
      if (s.stage == "frame") ev = s.ms;
    ms.push_back(be->kind() == BackendKind::Cuda && ev >= 0 ? ev : wall);
  }
  Row r;
  r.table = "scaling";
  r.backend = backendName(be->kind());
  r.precision = sizeof(T) == 4 ? "float32" : "float64";
  r.solver = solver.name();
  if (be->kind() == BackendKind::Cuda) r.path = st.path;
  r.spheres = std::int64_t(m.size());
  r.constraints = solvedConstraints(m);
  r.iterations = iterations;
  r.substeps = substeps;
  r.colors = st.colors;
  r.ms_frame = median(ms);
  r.ms_min = *std::min_element(ms.begin(), ms.end());
  r.ms_max = *std::max_element(ms.begin(), ms.end());
  r.mbytes_frame = frameBytes(m, iterations, substeps, solver.kind == PbdSolverKind::Jacobi) / 1e6;
  r.gbytes_per_s = r.mbytes_frame * 1e6 / (r.ms_frame * 1e-3) / 1e9;
  r.host_peak_mib = host.mib();
  r.device_peak_mib = bench::deviceUsedMiB(be->kind()) - dev0;
  r.constraints_per_s = double(r.constraints) * iterations * substeps / (r.ms_frame * 1e-3);
  r.residual_max = st.residual_max;
  r.residual_rms = st.residual_rms;
  if (g_profile) {
    p.profile_stages = true;
    st = be->advanceFrame(p, in);
  }
  for (const auto& s : st.stages) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s%s=%.3f", r.stages.empty() ? "" : " ", s.stage.c_str(), s.ms);
    r.stages += buf;
  }
  if (be->kind() == BackendKind::Cpu) {  // a loaded machine makes the CPU team back off to one thread
    char buf[64];
    std::snprintf(buf, sizeof buf, " team=%d/%zu", team_frames, ms.size());
    r.stages += buf;
  }
  return r;
}

// Speed/accuracy: mean tip deflection after `frames` frames of sagging, against a 200-iteration
// Gauss-Seidel reference run.
template <typename T>
double tipDeflection(BackendKind kind, Solve solver, std::int64_t n, int iterations, int substeps, int frames,
                     PbdFrameStats& st) {
  Vec3d size;
  const PbdModel<T> m = blockModel<T>(n, size);
  auto be = makePbdBackend<T>(kind);
  be->setModel(m);
  PbdStepParams<T> p;
  p.solver = solver.kind;
  p.chebyshev_rho = T(solver.rho);
  p.jacobi_omega = T(g_jacobi_omega);
  p.rotation_iterations = g_rotation_iterations;
  p.iterations = iterations;
  p.substeps = substeps;
  p.damping = T(5);
  p.volume_preservation = false;
  for (int f = 0; f < frames; ++f) {
    if (pastDeadline()) return std::nan("");  // cut by --budget: no deflection reported
    st = be->advanceFrame(p, PbdFrameInput<T>());
  }
  PbdState<T> s;
  be->getState(s);
  double tip = 0;
  int cnt = 0;
  for (std::size_t i = 0; i < m.size(); ++i)
    if (double(m.rest_positions[i].x) > size.x - 0.5 * kSpacing) {
      tip += double(m.rest_positions[i].z - s.positions[i].z);
      ++cnt;
    }
  return tip / std::max(1, cnt);
}

void printRow(const Row& r) {
  if (r.table == "scaling")
    std::printf("%-6s %-8s %-12s %-8s %8lld %9lld %4d %4d %5d %10.3f %12.3e %10.2e  %s\n", r.backend.c_str(),
                r.precision.c_str(), r.solver.c_str(), r.path.c_str(), (long long)r.spheres, (long long)r.constraints,
                r.iterations, r.substeps, r.colors, r.ms_frame, r.constraints_per_s, r.residual_max, r.stages.c_str());
  else
    std::printf("%-6s %-8s %-12s %8lld %4d %4d %10.3f %10.3e %10.3e %10.3e %9.2f%%\n", r.backend.c_str(),
                r.precision.c_str(), r.solver.c_str(), (long long)r.spheres, r.iterations, r.substeps, r.ms_frame,
                r.residual_max, r.residual_rms, r.deflection_m, 100.0 * r.deflection_err);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"PBD/XPBD metaball solver benchmark"};
  std::string backend = "auto", csv, precision = "float32";
  std::int64_t min_n = 100, max_n = 100000, cpu_max = 20000, accuracy_n = 570;
  int iterations = 10, substeps = 4, repeats = 20, fused_max = 4096,
      cluster_max = PbdStepParams<float>{}.cluster_max_particles, grid_max = PbdStepParams<float>{}.grid_max_particles;
  bool quick = false;
  double chebyshev_rho = 0;
  bool jacobi_only = false;
  std::vector<double> accuracy_rhos{0.5, 0.9};
  app.add_option("--backend", backend, "auto (CPU and, when present, CUDA) | cpu | cuda");
  app.add_option("--precision", precision, "float32 | float64");
  app.add_option("--min", min_n, "smallest sphere count");
  app.add_option("--max", max_n, "largest sphere count");
  app.add_option("--cpu-max", cpu_max, "largest sphere count timed on the CPU");
  app.add_option("--accuracy-spheres", accuracy_n, "sphere count of the residual/deflection vs iterations table");
  app.add_option("--iterations", iterations, "iterations per substep in the scaling table");
  app.add_option("--substeps", substeps, "substeps per 1/60 s frame");
  app.add_option("--repeats", repeats, "timed frames per point (median)");
  app.add_option("--fused-max", fused_max,
                 "CUDA: largest sphere count run by the fused single-block kernel (0: never; Jacobi: at most 256)");
  app.add_flag("--no-graph", g_no_graph,
               "CUDA: launch every frame directly (no CUDA graph), as a cut's rebuilt model is");
  app.add_option("--grid-max", grid_max,
                 "CUDA, Jacobi: largest sphere count run as one cooperative grid launch (0: never)");
  app.add_option("--cluster-max", cluster_max,
                 "CUDA, Jacobi: largest sphere count run by the thread-block cluster frame kernel (0: never)");
  app.add_flag("--jacobi-only", jacobi_only, "scaling table: Jacobi rows only (no Gauss-Seidel)");
  app.add_option(
      "--chebyshev-rho", chebyshev_rho,
      "Jacobi rows of the scaling table: Chebyshev acceleration with this spectral-radius estimate (0: off)");
  app.add_option("--accuracy-rhos", accuracy_rhos,
                 "the accuracy table's Chebyshev-accelerated Jacobi rows, one per estimate (empty: none)");
  app.add_option("--rotation-iterations", g_rotation_iterations,
                 "polar-decomposition steps per shape-matching cluster per projection (warm-started)");
  app.add_option("--jacobi-omega", g_jacobi_omega, "over-relaxation of the averaged Jacobi step, (0, 2)");
  app.add_option("--csv", csv, "write every row to this CSV file");
  app.add_flag("--quick", quick, "short run: up to 10^4 spheres, 5 repeats");
  double budget_s = 130.0;
  app.add_option("--row-seconds", g_row_seconds, "wall-time budget of one timed point (at least 3 frames are timed)");
  app.add_option("--budget", budget_s, "whole run: points that would start after this many seconds are skipped");
  app.add_flag("--profile", g_profile,
               "add a per-stage CUDA-event split (one extra unfused, ungraphed frame) to each row");
  CLI11_PARSE(app, argc, argv);
  try {
    const BackendKind requested = parseBackend(backend);
    if (precision != "float32" && precision != "float64")
      throw InputError("bench_pbd", "--precision", "float32 or float64");
    if (quick) {
      max_n = std::min<std::int64_t>(max_n, 10000);
      cpu_max = std::min<std::int64_t>(cpu_max, 3000);
      repeats = std::min(repeats, 5);
    }
    if (min_n < 8 || max_n < min_n || iterations < 1 || substeps < 1 || repeats < 1)
      throw InputError("bench_pbd", "arguments", "need 8 <= min <= max, iterations, substeps, repeats >= 1");
    if (!(g_row_seconds > 0) || !(budget_s > 0))
      throw InputError("bench_pbd", "--row-seconds/--budget", "must be positive");
    if (quick) g_row_seconds = std::min(g_row_seconds, 0.5);
    g_deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                        std::chrono::duration<double>(budget_s));
    std::vector<BackendKind> kinds;
    if (requested != BackendKind::Cuda) kinds.push_back(BackendKind::Cpu);
#if INCISION_HAVE_CUDA
    const bool have_gpu = cuda::queryDevices().device_count > 0;
#else
    const bool have_gpu = false;
#endif
    if (requested == BackendKind::Cuda && !have_gpu)
      throw InputError("bench_pbd", "--backend", "no usable CUDA device");
    if (have_gpu && requested != BackendKind::Cpu) kinds.push_back(BackendKind::Cuda);
    const bool f64 = precision == "float64";

    std::vector<std::int64_t> sizes;
    for (double n = double(min_n); n <= double(max_n) * 1.0001; n *= std::sqrt(10.0)) sizes.push_back(std::llround(n));
    if (accuracy_n >= min_n && accuracy_n <= max_n) sizes.push_back(accuracy_n);
    std::sort(sizes.begin(), sizes.end());

    std::vector<Row> rows;
    std::printf(
        "# scaling: %d iterations x %d substeps per 1/60 s frame, probe pressing, volume preservation near it\n",
        iterations, substeps);
    std::printf("%-6s %-8s %-12s %-8s %8s %9s %4s %4s %5s %10s %12s %10s  stages\n", "backend", "prec", "solver",
                "path", "spheres", "constr", "it", "sub", "cols", "ms/frame", "constr/s", "resid_m");
    for (BackendKind k : kinds)
      for (std::int64_t n : sizes) {
        if (k == BackendKind::Cpu && n > cpu_max) continue;
        for (Solve s : {Solve{PbdSolverKind::Jacobi, chebyshev_rho}, Solve{PbdSolverKind::GaussSeidel, 0.0}}) {
          if (jacobi_only && s.kind == PbdSolverKind::GaussSeidel) continue;
          if (pastDeadline()) {
            ++g_skipped;
            continue;
          }
          const Row r =
              f64 ? timeFrames<double>(k, s, n, iterations, substeps, repeats, fused_max, cluster_max, grid_max)
                  : timeFrames<float>(k, s, n, iterations, substeps, repeats, fused_max, cluster_max, grid_max);
          printRow(r);
          rows.push_back(r);
          if (k == BackendKind::Cuda && r.path != "launches" &&
              !pastDeadline()) {  // the same on per-phase launches, for comparison
            const Row u = f64 ? timeFrames<double>(k, s, n, iterations, substeps, repeats, 0, 0, 0)
                              : timeFrames<float>(k, s, n, iterations, substeps, repeats, 0, 0, 0);
            printRow(u);
            rows.push_back(u);
          }
        }
      }

    // Speed/accuracy trade: deflection error against iterations (reference: 200 Gauss-Seidel iterations).
    const int frames = quick ? 30 : 90;
    std::printf(
        "# accuracy: %lld spheres, %d frames of sagging; deflection error vs a 200-iteration Gauss-Seidel run\n",
        (long long)accuracy_n, frames);
    std::printf("%-6s %-8s %-12s %8s %4s %4s %10s %10s %10s %10s %10s\n", "backend", "prec", "solver", "spheres", "it",
                "sub", "ms/frame", "resid_max", "resid_rms", "tip_m", "err");
    for (BackendKind k : kinds) {
      if (pastDeadline()) {
        g_skipped += 12;
        continue;
      }
      PbdFrameStats st;
      const Solve gs{PbdSolverKind::GaussSeidel, 0.0};
      std::vector<Solve> solves{Solve{PbdSolverKind::Jacobi, 0.0}};
      for (double rho : accuracy_rhos) solves.push_back(Solve{PbdSolverKind::Jacobi, rho});
      solves.push_back(gs);
      const double ref = f64 ? tipDeflection<double>(k, gs, accuracy_n, 200, substeps, frames, st)
                             : tipDeflection<float>(k, gs, accuracy_n, 200, substeps, frames, st);
      for (const Solve& s : solves)
        for (int it : {1, 2, 3, 4, 5, 10, 20, 50}) {
          if (pastDeadline()) {
            ++g_skipped;
            continue;
          }
          Row r = f64 ? timeFrames<double>(k, s, accuracy_n, it, substeps, std::max(3, repeats / 2), fused_max,
                                           cluster_max, grid_max)
                      : timeFrames<float>(k, s, accuracy_n, it, substeps, std::max(3, repeats / 2), fused_max,
                                          cluster_max, grid_max);
          r.table = "accuracy";
          r.deflection_m = f64 ? tipDeflection<double>(k, s, accuracy_n, it, substeps, frames, st)
                               : tipDeflection<float>(k, s, accuracy_n, it, substeps, frames, st);
          r.residual_max = st.residual_max;
          r.residual_rms = st.residual_rms;
          r.deflection_err = ref > 0 ? std::fabs(r.deflection_m - ref) / ref : 0.0;
          if (std::isnan(r.deflection_m) || std::isnan(ref)) ++g_skipped;
          printRow(r);
          rows.push_back(r);
        }
    }

    if (!csv.empty()) {
      std::ofstream out(csv);
      if (!out) throw InputError(csv, "--csv", "cannot write");
      out << "table,backend,precision,solver,path,spheres,constraints,iterations,substeps,colors,ms_frame,constraints_"
             "per_s,"
             "residual_max_m,residual_rms_m,deflection_m,deflection_rel_err,ms_frame_min,ms_frame_max,mbytes_frame,"
             "gbytes_per_s,host_peak_mib,device_peak_mib\n";
      for (const Row& r : rows)
        out << r.table << ',' << r.backend << ',' << r.precision << ',' << r.solver << ',' << r.path << ',' << r.spheres
            << ',' << r.constraints << ',' << r.iterations << ',' << r.substeps << ',' << r.colors << ',' << r.ms_frame
            << ',' << r.constraints_per_s << ',' << r.residual_max << ',' << r.residual_rms << ',' << r.deflection_m
            << ',' << r.deflection_err << ',' << r.ms_min << ',' << r.ms_max << ',' << r.mbytes_frame << ','
            << r.gbytes_per_s << ',' << r.host_peak_mib << ',' << r.device_peak_mib << '\n';
    }
    // Summary: the liver-sized case (accuracy_n spheres) at the scaling table's settings, fastest per backend.
    std::string summary = "bench_pbd: " + std::to_string(accuracy_n) + " spheres, " + std::to_string(iterations) + "x" +
                          std::to_string(substeps) + " it/frame:";
    for (BackendKind k : kinds) {
      double best = 1e30;
      std::string which;
      for (const Row& r : rows)
        if (r.table == "scaling" && r.spheres > 0 && r.backend == backendName(k) &&
            std::llabs(r.spheres - accuracy_n) <= accuracy_n / 5 && r.ms_frame < best) {
          best = r.ms_frame;
          which = r.solver;
        }
      char buf[160];
      if (best < 1e30) {
        std::snprintf(buf, sizeof buf, " %s %.3f ms/frame (%s);", backendName(k), best, which.c_str());
        summary += buf;
      }
    }
    if (g_skipped > 0) {
      char buf[96];
      std::snprintf(buf, sizeof buf, " %d points skipped (--budget %.0f s);", g_skipped, budget_s);
      summary += buf;
    }
    std::printf("%s\n", summary.c_str());
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
