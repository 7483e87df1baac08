// Scaling of skinning and of a whole frame of the default scene against particle count (CPU and CUDA, float32/64).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "base/parallel.h"
#include "bench/bench_memory.h"
#include "bench/mls_traffic.h"
#include "host/app/runner.h"
#include "host/assembly/pbd_builders.h"
#include "host/assembly/skin_binding.h"
#include "host/backends/backend_choice.h"
#include "host/scene/embedded_scenes.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "kernels/device_info.h"
#include "model/backend.h"
#include "model/input_error.h"
#if INCISION_HAVE_CUDA
#include <cuda_runtime.h>

#include "kernels/cuda_check.h"
#include "kernels/skinning_cuda.h"
#endif

using namespace inc;
using bench::deviceUsedMiB;
using bench::HostPeak;

namespace {

struct Row {
  std::string suite, backend, precision;
  std::int64_t n = 0;  // particles (frame) / skinned vertices (skinning)
  double ms_median = 0, ms_min = 0, ms_max = 0, items_per_s = 0, mbytes = 0, gbytes_per_s = 0;
  double host_peak_mib = 0;    // peak resident set of the process during the row (see HostPeak)
  double device_mib = 0;       // what the row's own buffers hold on the device (model report / explicit allocations)
  double device_peak_mib = 0;  // device memory in use above the row's start, sampled after the build and each run
  int substeps = 0;            // frame: substeps per frame (median)
};

void finish(Row& r, std::vector<double> ms, const HostPeak& host) {
  std::sort(ms.begin(), ms.end());
  r.ms_median = ms.size() % 2 ? ms[ms.size() / 2] : 0.5 * (ms[ms.size() / 2 - 1] + ms[ms.size() / 2]);
  r.ms_min = ms.front();
  r.ms_max = ms.back();
  r.items_per_s = r.ms_median > 0 ? double(r.n) / (r.ms_median * 1e-3) : 0.0;
  r.gbytes_per_s = r.ms_median > 0 ? r.mbytes * 1e6 / (r.ms_median * 1e-3) / 1e9 : 0.0;
  r.host_peak_mib = host.mib();
}

// Skinning: n vertices at random points in a 4:1:1 box bound (k = 4) to a lattice of about n / 8 spheres,
// blended with per-sphere rotations (identity here; the cost is the same).
template <typename T>
Row skinning(std::int64_t n, BackendKind be, int repeats) {
  HostPeak host;
  host.reset();
  const double dev0 = deviceUsedMiB(be);
  (void)dev0;  // read on the CUDA path only
  Row r;
  r.suite = "skinning";
  r.backend = backendName(be);
  r.precision = sizeof(T) == 4 ? "float32" : "float64";
  r.n = n;
  // Lattice of about `spheres` spheres at 2.5 mm filling a 4a x a x a box.
  const double spheres = std::max(64.0, double(n) / 8.0), d = 0.0025;
  const double edge = d * std::max(1.0, std::cbrt(spheres / 4.0) - 1.0);
  const Vec3d hi{4.0 * edge, edge, edge};
  const MetaballModel mb = makeLatticeMetaballs(Vec3d(0, 0, 0), hi, d, 0.75, 1000.0);
  TriangleMesh surf;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> ux(0, hi.x), uy(0, hi.y), uz(0, hi.z);
  surf.vertices.resize(std::size_t(n));
  for (auto& v : surf.vertices) v = Vec3d(ux(rng), uy(rng), uz(rng));
  const SkinBinding b = bindSkin(surf, mb, 4);
  const SkinArrays<T> a = skinArrays<T>(b);
  std::vector<Vec3<T>> centres(mb.size());
  for (std::size_t i = 0; i < mb.size(); ++i)
    centres[i] = Vec3<T>(T(mb.rest_centers[i].x), T(mb.rest_centers[i].y), T(mb.rest_centers[i].z + 0.001));
  std::vector<Mat3<T>> rot(mb.size(), Mat3<T>::identity());
  // Compulsory traffic per blend: rest vertex + output (2 x 3T), k x (index + weight), k x (centre + rotation)
  // gathered.
  r.mbytes = double(n) * (6.0 * sizeof(T) + 4.0 * (4.0 + sizeof(T)) + 4.0 * 12.0 * sizeof(T)) / 1e6;
  std::vector<double> ms;
  if (be == BackendKind::Cpu) {
    std::vector<Vec3<T>> out(static_cast<std::size_t>(n));
    const skin::SkinView<T> view = a.view();
    for (int it = -1; it < repeats; ++it) {
      const auto t0 = std::chrono::steady_clock::now();
      cpu::parallelFor(n, [&](std::int64_t v) { out[v] = skin::skinVertex(view, int(v), centres.data(), rot.data()); });
      const auto t1 = std::chrono::steady_clock::now();
      if (it >= 0) ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
  }
#if INCISION_HAVE_CUDA
  else {
    cuda::SkinningCuda<T> sk;
    sk.upload(a.view(), int(mb.size()), a.triangles, a.tri_offsets, a.tri_of_vertex);
    Vec3<T>* d_c = nullptr;
    Mat3<T>* d_r = nullptr;
    INC_CUDA(cudaMalloc(&d_c, centres.size() * sizeof(Vec3<T>)));
    INC_CUDA(cudaMalloc(&d_r, rot.size() * sizeof(Mat3<T>)));
    INC_CUDA(cudaMemcpy(d_c, centres.data(), centres.size() * sizeof(Vec3<T>), cudaMemcpyHostToDevice));
    INC_CUDA(cudaMemcpy(d_r, rot.data(), rot.size() * sizeof(Mat3<T>), cudaMemcpyHostToDevice));
    cudaEvent_t e0, e1;
    INC_CUDA(cudaEventCreate(&e0));
    INC_CUDA(cudaEventCreate(&e1));
    for (int it = -1; it < repeats; ++it) {
      INC_CUDA(cudaEventRecord(e0));
      sk.deformDevice(d_c, d_r);
      INC_CUDA(cudaEventRecord(e1));
      INC_CUDA(cudaEventSynchronize(e1));
      float t = 0;
      INC_CUDA(cudaEventElapsedTime(&t, e0, e1));
      if (it >= 0) ms.push_back(double(t));
    }
    // Skinning has no model report: its buffers (uploaded binding, centres, rotations, output) are what the
    // device holds above the row's start.
    r.device_peak_mib = deviceUsedMiB(be) - dev0;
    r.device_mib = r.device_peak_mib;
    INC_CUDA(cudaEventDestroy(e0));
    INC_CUDA(cudaEventDestroy(e1));
    INC_CUDA(cudaFree(d_c));
    INC_CUDA(cudaFree(d_r));
  }
#endif
  finish(r, ms, host);
  return r;
}

// A whole frame (1/60 s, as many substeps as stability needs) of the default scene with its spacing scaled so
// the body has about n particles; host wall time of advance() (it returns after the frame's report, so the
// device is synchronised). Bytes: the compulsory traffic of the frame's MLS substeps and its reduction
// (bench/mls_traffic.h, mean neighbours from the model); 0 when the scene has other models than MLS.
Row frame(std::int64_t n, BackendKind be, Precision p, int repeats) {
  HostPeak host;
  host.reset();
  const double dev0 = deviceUsedMiB(be);
  Row r;
  r.suite = "frame";
  r.backend = backendName(be);
  r.precision = precisionName(p);
  // The MLS cantilever (the embedded `beam`), refined: the frame this suite has always scaled.
  Scene s = parseScene(findEmbeddedScene("beam")->json, "<embedded:beam>", ".");
  const GeometrySpec& g = s.geometry;
  const double vol = g.size.x * g.size.y * g.size.z;
  s.geometry.spacing = std::cbrt(vol / double(n));
  s.solver.precision = p;
  auto models = createSceneModels(compileScene(s), be);
  for (const auto& m : models) r.n += std::int64_t(m->particleCount());
  double dev_peak = deviceUsedMiB(be) - dev0;
  const bool mls_only = models.size() == 1 && models[0]->name() == "mls";
  std::vector<double> ms, mbytes;
  std::vector<int> substeps;
  for (int it = -1; it < repeats; ++it) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<FrameReport> reps;
    for (auto& m : models) reps.push_back(m->advance(s.solver.frame_dt));
    const auto t1 = std::chrono::steady_clock::now();
    dev_peak = std::max(dev_peak, deviceUsedMiB(be) - dev0);
    if (it < 0) continue;
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    substeps.push_back(reps.front().substeps);
    if (mls_only) {
      const auto nb = reps.front().counters.find("mean_neighbours");
      const double nnz = (nb == reps.front().counters.end() ? 0.0 : nb->second) * double(r.n);
      mbytes.push_back(bench::mlsFrameBytes(r.n, nnz, p == Precision::Float64 ? 8 : 4, reps.front().substeps) / 1e6);
    }
  }
  std::sort(substeps.begin(), substeps.end());
  r.substeps = substeps[substeps.size() / 2];
  std::sort(mbytes.begin(), mbytes.end());
  r.mbytes = mbytes.empty() ? 0.0 : mbytes[mbytes.size() / 2];
  for (const auto& m : models) r.device_mib += double(m->memory().device_bytes) / 1048576.0;
  r.device_peak_mib = dev_peak;
  finish(r, ms, host);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_scaling: skinning and whole-frame cost against particle count"};
  std::string backend = "auto", precision = "both", suites = "skinning,frame", csv;
  std::int64_t lo = 1000, hi = 16000000, cpu_max = 1000000;
  int repeats = 7;
  double budget_s = 120.0;
  bool quick = false;
  app.add_option("--backend", backend, "cpu | cuda | auto (CUDA when usable, plus the CPU up to --cpu-max)");
  app.add_option("--precision", precision, "float32 | float64 | both");
  app.add_option("--suite", suites, "comma list: skinning, frame");
  app.add_option("--min", lo, "smallest count");
  app.add_option("--max", hi, "largest count on the GPU");
  app.add_option("--cpu-max", cpu_max, "largest count on the CPU");
  app.add_option("--repeats", repeats, "timed runs per point after one warm-up (median, min, max reported)");
  app.add_option("--time-budget-s", budget_s, "stop growing a series once its last point took longer than this / 8");
  app.add_option("--csv", csv, "CSV output");
  app.add_flag("--quick", quick, "counts up to 1e4 (GPU) / 4e3 (CPU), 3 repeats: checks it runs");
  CLI11_PARSE(app, argc, argv);
  std::vector<Row> rows;
  try {
    if (quick) {
      hi = std::min<std::int64_t>(hi, 10000);
      cpu_max = std::min<std::int64_t>(cpu_max, 4000);
      repeats = std::min(repeats, 3);
    }
    if (lo < 100 || hi < lo || repeats < 1)
      throw InputError("", "--min/--max/--repeats", "need 100 <= min <= max, repeats >= 1");
    std::vector<BackendKind> backends;
    const BackendKind req = parseBackend(backend);
    if (req == BackendKind::Cpu) {
      backends = {BackendKind::Cpu};
    } else {
      const BackendChoice c = resolveBackend(req);
      backends.push_back(c.kind);
      if (req == BackendKind::Auto && c.kind == BackendKind::Cuda && cpu_max >= lo)
        backends.push_back(BackendKind::Cpu);
    }
    std::vector<Precision> precs;
    if (precision == "float32" || precision == "both") precs.push_back(Precision::Float32);
    if (precision == "float64" || precision == "both") precs.push_back(Precision::Float64);
    if (precs.empty()) throw InputError("", "--precision", "float32 | float64 | both");
    // The CSV is written row by row, so a run stopped by a time limit keeps what it measured.
    std::ofstream f;
    if (!csv.empty()) {
      f.open(csv);
      f << "suite,backend,precision,n,ms_median,ms_min,ms_max,items_per_s,mbytes,gbytes_per_s,host_peak_mib,device_mib,"
           "device_peak_mib,substeps\n";
      if (!f) throw InputError(csv, "--csv", "cannot write the file");
    }
    std::printf("%-9s %-5s %-8s %10s %10s %10s %10s %12s %9s %9s %10s %9s %9s %6s\n", "suite", "backend", "precision",
                "n", "ms median", "min", "max", "items/s", "MB", "GB/s", "host MiB", "dev MiB", "dev peak", "subst");
    for (const std::string suite : {"skinning", "frame"}) {
      if (suites.find(suite) == std::string::npos) continue;
      for (BackendKind be : backends)
        for (Precision p : precs) {
          std::int64_t top = be == BackendKind::Cpu ? std::min(hi, cpu_max) : hi;
          // A whole frame costs ~N^(4/3) (finer spacing, more substeps): --quick keeps it to one small point.
          if (quick && suite == std::string("frame")) top = std::min(top, lo);
          for (std::int64_t n = lo; n <= top; n *= 4) {
            const auto t0 = std::chrono::steady_clock::now();
            Row r = suite == "frame" ? frame(n, be, p, repeats)
                                     : (p == Precision::Float32 ? skinning<float>(n, be, repeats)
                                                                : skinning<double>(n, be, repeats));
            std::printf("%-9s %-5s %-8s %10lld %10.3f %10.3f %10.3f %12.3e %9.2f %9.2f %10.1f %9.1f %9.1f %6d\n",
                        r.suite.c_str(), r.backend.c_str(), r.precision.c_str(), (long long)r.n, r.ms_median, r.ms_min,
                        r.ms_max, r.items_per_s, r.mbytes, r.gbytes_per_s, r.host_peak_mib, r.device_mib,
                        r.device_peak_mib, r.substeps);
            std::fflush(stdout);
            rows.push_back(r);
            if (f.is_open()) {
              f << r.suite << ',' << r.backend << ',' << r.precision << ',' << r.n << ',' << r.ms_median << ','
                << r.ms_min << ',' << r.ms_max << ',' << r.items_per_s << ',' << r.mbytes << ',' << r.gbytes_per_s
                << ',' << r.host_peak_mib << ',' << r.device_mib << ',' << r.device_peak_mib << ',' << r.substeps
                << std::endl;
            }
            // The next point is ~4x the work: skip it when it would not fit the budget.
            if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * 4.0 > budget_s / 2.0)
              break;
            if (n < top && n * 4 > top) n = top / 4;  // end exactly at the top count
          }
        }
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "bench_scaling: %s\n", e.what());
    return 2;
  }
  double best = 0, best_gbs = 0;
  for (const Row& r : rows) {
    best = std::max(best, r.items_per_s);
    if (r.backend == "cuda") best_gbs = std::max(best_gbs, r.gbytes_per_s);
  }
  // Achieved bandwidth against the device's measured peak (a device-to-device copy, read + write).
  const double peak = best_gbs > 0 ? cuda::measureCopyBandwidthGbs() : 0.0;
  char frac[96] = "";
  if (peak > 0)
    std::snprintf(frac, sizeof frac, "; best GPU row %.0f GB/s = %.0f %% of the measured %.0f GB/s copy peak", best_gbs,
                  100.0 * best_gbs / peak, peak);
  std::printf("bench_scaling: %zu points, largest n %lld, best throughput %.3e items/s%s\n", rows.size(),
              rows.empty() ? 0LL
                           : (long long)std::max_element(rows.begin(), rows.end(),
                                                         [](const Row& a, const Row& b) { return a.n < b.n; })
                                 ->n,
              best, frac);
  return 0;
}
