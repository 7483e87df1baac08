// Benchmark: grid neighbour search rebuild + self-query time against particle count (jittered lattice, ~30 neighbours).
#include <omp.h>
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
#include "cpu_fallback/neighbor_search_cpu.h"
#include "host/backends/backend_choice.h"
#include "kernels/device_info.h"
#include "model/backend.h"
#include "model/input_error.h"
#if INCISION_HAVE_CUDA
#include <cuda_runtime.h>

#include "kernels/cuda_check.h"
#include "kernels/neighbor_search_cuda.h"
#endif

namespace {

using namespace inc;

// H100 SXM5 (HBM3, 80 GB) datasheet bandwidth, used when the driver does not report clock and bus width.
constexpr double kH100PeakGbs = 3350.0;

// Radius for ~30 neighbours at unit density: (4/3) pi r^3 = 31 (the ball holds the particle itself too).
constexpr double kRadius = 1.95;

// n particles on a unit lattice (x fastest), each moved by up to +-0.25 per axis: density 1, no voids.
// shuffle: list them in random order (the storage order then differs from the input order everywhere).
bool g_shuffle = false;
// storage: lists in storage order (querySelfStorage: rows and entries are storage slots, no permutation).
bool g_storage = false;
// CPU: new lists from every call (the by-value API) instead of lists reused between calls (as the GPU reuses its
// DeviceNeighborLists): allocating and first touching the ~120 MB of 1e6 lists is then inside the timing.
bool g_fresh_lists = false;
template <typename T>
std::vector<Vec3<T>> jitteredLattice(std::size_t n, unsigned seed) {
  const std::size_t m = std::size_t(std::ceil(std::cbrt(double(n)) - 1e-9));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.25, 0.25);
  std::vector<Vec3<T>> p;
  p.reserve(n);
  for (std::size_t k = 0; k < m && p.size() < n; ++k)
    for (std::size_t j = 0; j < m && p.size() < n; ++j)
      for (std::size_t i = 0; i < m && p.size() < n; ++i)
        p.emplace_back(T(double(i) + u(rng)), T(double(j) + u(rng)), T(double(k) + u(rng)));
  if (g_shuffle) std::shuffle(p.begin(), p.end(), rng);
  return p;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

// Compulsory memory traffic per particle (bytes), the model of docs/neighbor-search.md: every array a
// kernel streams is counted once per kernel; neighbour reads inside the traversal are assumed to hit the
// caches (threads of a warp query neighbouring cells), so they are not counted. A lower bound on DRAM traffic.
struct TrafficModel {
  double build, query;
};

// gpu: the CUDA pipeline (float points also get a 16-byte packed copy for the queries, and the query is one
// traversal that stages sorted rows, then a copy); otherwise the CPU's (one traversal straight into lists).
TrafficModel trafficModel(std::size_t point_bytes, double neighbours, double buckets_per_point, int bucket_bits,
                          int morton_bits, bool morton, bool gpu, bool storage) {
  const double P = double(point_bytes);
  const double Q = gpu && point_bytes == 12 ? 16.0 : P;  // the point record the query reads
  auto sortPairs = [](int bits) {  // CUB onesweep: a key histogram pass, then 8-bit digit passes over key+value
    return 4.0 + 16.0 * double((bits + 7) / 8);
  };
  double build = P;                  // bounding-box reduction reads every point
  build += 4.0 * buckets_per_point;  // histogram memset
  build += P + 4.0 + 4.0 + 8.0;      // bucket keys: read point, write key and iota, histogram atomic (r+w)
  build += sortPairs(bucket_bits);   // sort (key, index) pairs by bucket
  build += 4.0 + 2.0 * P + 4.0;      // gather: read perm and point, write sorted point and inverse
  if (Q != P) build += Q;            // ... and the packed copy
  build += 8.0 * buckets_per_point;  // exclusive scan of the histogram: read + write
  if (morton) build += (P + 8.0) + sortPairs(morton_bits);  // Morton keys + their sort before the rest
  if (!gpu) {
    // traversal: read own point (and perm for original-order lists), append the list to a block buffer; then
    // copy it into place
    return {build, P + (storage ? 0.0 : 4.0) + 4.0 * neighbours + 8.0 + 8.0 * neighbours};
  }
  // storage order: one traversal reads its own point and writes its offset and its row in place
  if (storage) return {build, Q + 8.0 + 4.0 * neighbours};
  double query = Q + 4.0 + 4.0 + 4.0 * neighbours;  // count+stage: own point, perm; write count, staged row
  query += 4.0 + 8.0;                               // scan: read count, write int64 offset
  query += 4.0 + 8.0 + 8.0 * neighbours;            // copy: perm, offset; read the staged row, write the indices
  return {build, query};
}

int keyBits(std::uint64_t count) {
  int b = 1;
  while (b < 32 && (std::uint64_t(1) << b) < count) ++b;
  return b;
}

struct Row {
  std::string backend, precision;
  std::size_t n = 0;
  double neighbours = 0, build_ms = 0, query_ms = 0, total_ms = 0, bytes = 0, gbs = 0, peak_fraction = 0, target_ms = 0;
  double total_min_ms = 0, total_max_ms = 0;      // spread of the timed repeats
  double host_peak_mib = 0, device_peak_mib = 0;  // bench/bench_memory.h: the row's peaks
  bool hashed = false;
  double cell_factor = 0;
};

// Issue 3 targets: GPU 0.5 ms at 1e6 and 10 ms at 1.6e7, linear in between; CPU 300 ms at 1e6.
double targetMs(bool gpu, std::size_t n) {
  if (!gpu) return n == 1000000 ? 300.0 : 0.0;
  if (n < 1000000 || n > 16000000) return 0.0;
  return 0.5 + (10.0 - 0.5) * double(n - 1000000) / 15e6;
}

template <typename T>
Row runCpu(std::size_t n, int repeats, bool morton, double cell_factor) {
  bench::HostPeak host;
  host.reset();
  const auto pts = jitteredLattice<T>(n, 1234);
  const T r = T(kRadius);
  cpu::GridNeighborSearch<T> s;
  NeighborLists l;
  std::vector<double> tb, tq, tt;
  for (int rep = -1; rep < repeats; ++rep) {  // rep -1: warm-up
    const auto t0 = std::chrono::steady_clock::now();
    s.build(pts, T(kRadius * cell_factor), morton);
    const auto t1 = std::chrono::steady_clock::now();
    if (g_fresh_lists)
      l = g_storage ? s.querySelfStorage(r) : s.querySelf(r);
    else if (g_storage)
      s.querySelfStorage(r, l);
    else
      s.querySelf(r, l);
    const auto t2 = std::chrono::steady_clock::now();
    if (rep < 0) continue;
    tb.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    tq.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    tt.push_back(std::chrono::duration<double, std::milli>(t2 - t0).count());
  }
  Row row;
  row.backend = "cpu";
  row.n = n;
  row.total_min_ms = *std::min_element(tt.begin(), tt.end());
  row.total_max_ms = *std::max_element(tt.begin(), tt.end());
  row.host_peak_mib = host.mib();
  row.neighbours = double(l.indices.size()) / double(std::max<std::size_t>(n, 1));
  row.build_ms = median(tb);
  row.query_ms = median(tq);
  row.total_ms = median(tt);
  row.hashed = s.hashed();
  const auto& p = s.params();
  const double used = p.dense ? double(p.dims[0]) * p.dims[1] * p.dims[2] : double(p.bucket_mask) + 1.0;
  const TrafficModel m = trafficModel(sizeof(Vec3<T>), row.neighbours, used / double(n), keyBits(std::uint64_t(used)),
                                      30, morton, false, g_storage);
  row.bytes = m.build + m.query;
  row.gbs = row.bytes * double(n) / (row.total_ms * 1e-3) / 1e9;
  row.target_ms = targetMs(false, n);
  return row;
}

#if INCISION_HAVE_CUDA
template <typename T>
Row runCuda(std::size_t n, int repeats, bool morton, double cell_factor, double peak_gbs, bool profile) {
  bench::HostPeak host;
  host.reset();
  const double dev0 = bench::deviceUsedMiB(BackendKind::Cuda);
  const auto pts = jitteredLattice<T>(n, 1234);
  const T r = T(kRadius);
  cuda::DeviceBuffer<Vec3<T>> d_pts;
  d_pts.upload(pts);
  cuda::GridNeighborSearch<T> s;
  cuda::DeviceNeighborLists out;
  cudaEvent_t e0, e1, e2;
  INC_CUDA(cudaEventCreate(&e0));
  INC_CUDA(cudaEventCreate(&e1));
  INC_CUDA(cudaEventCreate(&e2));
  std::vector<double> tb, tq, tt;
  for (int rep = -2; rep < repeats; ++rep) {  // two warm-ups: allocations happen there, not in the timings
    INC_CUDA(cudaEventRecord(e0));
    s.build(d_pts.data(), n, T(kRadius * cell_factor), morton);
    INC_CUDA(cudaEventRecord(e1));
    if (g_storage)
      s.querySelfStorage(r, out);
    else
      s.querySelf(r, out);
    INC_CUDA(cudaEventRecord(e2));
    INC_CUDA(cudaEventSynchronize(e2));
    if (rep < 0) continue;
    float a = 0, b = 0;
    INC_CUDA(cudaEventElapsedTime(&a, e0, e1));
    INC_CUDA(cudaEventElapsedTime(&b, e1, e2));
    tb.push_back(a);
    tq.push_back(b);
    tt.push_back(double(a) + double(b));
  }
  INC_CUDA(cudaEventDestroy(e0));
  INC_CUDA(cudaEventDestroy(e1));
  INC_CUDA(cudaEventDestroy(e2));
  // Every buffer of the search is allocated by the warm-ups and still held: the row's device memory.
  const double dev_peak = bench::deviceUsedMiB(BackendKind::Cuda) - dev0;
  if (profile) {
    // Separate profiled runs (events between the stages add a little host work, so the table above is
    // timed without them): median milliseconds per stage.
    s.setProfiling(true);
    std::vector<std::string> names;
    std::vector<std::vector<double>> ms;
    for (int rep = 0; rep < std::max(repeats, 3); ++rep) {
      s.build(d_pts.data(), n, T(kRadius * cell_factor), morton);
      if (g_storage)
        s.querySelfStorage(r, out);
      else
        s.querySelf(r, out);
      const auto stages = s.takeProfile();
      if (names.empty())
        for (const auto& st : stages) names.push_back(st.first);
      ms.resize(names.size());
      for (std::size_t i = 0; i < stages.size() && i < names.size(); ++i) ms[i].push_back(stages[i].second);
    }
    s.setProfiling(false);
    std::printf("profile cuda n=%zu:", n);
    for (std::size_t i = 0; i < names.size(); ++i) std::printf(" %s=%.4f", names[i].c_str(), median(ms[i]));
    std::printf(" (ms, median)\n");
  }
  Row row;
  row.backend = "cuda";
  row.n = n;
  row.total_min_ms = *std::min_element(tt.begin(), tt.end());
  row.total_max_ms = *std::max_element(tt.begin(), tt.end());
  row.host_peak_mib = host.mib();
  row.device_peak_mib = dev_peak;
  row.neighbours = double(out.indices.size()) / double(std::max<std::size_t>(n, 1));
  row.build_ms = median(tb);
  row.query_ms = median(tq);
  row.total_ms = median(tt);
  row.hashed = s.hashed();
  // The GPU build sizes its cell table and sort key width by the bucket count (not the occupied cells: it does
  // not wait for the grid parameters), so the model counts that table.
  const double used = double(neighborBucketCount(n)) + 1.0;
  const auto& p = s.params();
  const int max_dim = std::max(p.dims[0], std::max(p.dims[1], p.dims[2]));
  const int morton_bits = std::max(1, std::min(30, 3 * (keyBits(std::uint64_t(max_dim)) - p.morton_shift)));
  const TrafficModel m =
      trafficModel(sizeof(Vec3<T>), row.neighbours, used / double(n), keyBits(std::uint64_t(neighborBucketCount(n))),
                   morton_bits, morton, true, g_storage);
  row.bytes = m.build + m.query;
  row.gbs = row.bytes * double(n) / (row.total_ms * 1e-3) / 1e9;
  row.peak_fraction = peak_gbs > 0 ? row.gbs / peak_gbs : 0.0;
  row.target_ms = targetMs(true, n);
  return row;
}
#endif

std::vector<std::size_t> sizes(std::size_t lo, std::size_t hi, bool quick) {
  std::vector<std::size_t> v;
  if (quick) {
    for (std::size_t n : {lo, std::size_t(100000), std::size_t(1000000)})
      if (n >= lo && n <= hi && (v.empty() || n > v.back())) v.push_back(n);
    return v;
  }
  // four sizes per decade from lo, then hi itself
  for (int k = 0;; ++k) {
    const std::size_t n = std::size_t(std::llround(double(lo) * std::pow(10.0, k / 4.0)));
    if (n >= hi) break;
    v.push_back(n);
  }
  v.push_back(hi);
  return v;
}

void printRow(const Row& r) {
  std::printf("%-5s %-6s %10zu %7.2f %11.4f %11.4f %11.4f %9.2f %8.1f %8.1f %7.1f%% %10s %s\n", r.backend.c_str(),
              r.precision.c_str(), r.n, r.neighbours, r.build_ms, r.query_ms, r.total_ms,
              r.total_ms * 1e6 / double(r.n), r.bytes, r.gbs, 100.0 * r.peak_fraction,
              r.target_ms > 0 ? (std::to_string(r.target_ms).substr(0, 6)).c_str() : "-", r.hashed ? "hashed" : "");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Grid neighbour search: rebuild + self-query time against particle count (jittered lattice)"};
  std::string backend_text = "auto", precision = "float", csv;
  std::size_t lo = 10000, hi = 1000000, cpu_max = 0;
  int repeats = 0, cpu_threads = 0;
  bool quick = false, morton = false, profile = false;
  double cell_factor = 0.0;  // 0: what findNeighbors picks for a dense cloud (CPU 0.5, CUDA 1.0)
  app.add_option("--backend", backend_text, "cpu | cuda | auto");
  app.add_option("--min", lo, "smallest particle count");
  app.add_option("--max", hi, "largest particle count");
  app.add_option("--cpu-max", cpu_max, "also run the CPU fallback from --min up to this count (0: no)");
  app.add_option("--precision", precision, "float | double")->check(CLI::IsMember({"float", "double"}));
  app.add_option("--repeats", repeats, "timed repeats per size after warm-up (default 10 GPU, 5 CPU)");
  app.add_option("--cpu-threads", cpu_threads,
                 "OpenMP threads for the CPU runs (0: OMP_NUM_THREADS or all cores;"
                 " 2 matches the issue's 2-core target)");
  app.add_option("--cell-factor", cell_factor, "grid cell edge / radius (default: CPU 0.5, CUDA 1.0, as findNeighbors)")
      ->check(CLI::Range(0.0, 10.0));
  app.add_flag("--morton", morton, "store the grid in Z order");
  app.add_flag("--shuffle", g_shuffle, "list the particles in random order instead of lattice order");
  app.add_flag("--storage-order", g_storage,
               "lists in storage order (querySelfStorage: no permutation; one GPU traversal writes rows in place)");
  app.add_flag("--cpu-fresh-lists", g_fresh_lists,
               "CPU: new lists from every call (by-value API) instead of reusing the lists between repeats");
  app.add_option("--csv", csv, "write the rows as CSV here");
  app.add_flag("--profile", profile, "GPU: also print the median time of every build / query stage (CUDA events)");
  app.add_flag("--quick", quick, "a short run: at most three sizes, three repeats");
  CLI11_PARSE(app, argc, argv);

  try {
    if (lo < 1 || hi < lo) throw InputError("", "--min/--max", "need 1 <= min <= max");
    if (cpu_threads < 0) throw InputError("", "--cpu-threads", "must be >= 0");
    if (cpu_threads > 0) omp_set_num_threads(cpu_threads);
    const BackendChoice choice = resolveBackend(parseBackend(backend_text));
    const bool gpu = choice.kind == BackendKind::Cuda;
    const cuda::DeviceReport dev = cuda::queryDevices();
    double peak = 0.0;
    std::string peak_note = "-";
    if (gpu) {
      // Fractions are of the measured peak (a device-to-device copy); the clock-and-bus figure is printed beside.
      const double measured = cuda::measureCopyBandwidthGbs();
      const double nominal = dev.peak_bandwidth_gbs > 0 ? dev.peak_bandwidth_gbs : kH100PeakGbs;
      peak = measured > 0 ? measured : nominal;
      char note[160];
      std::snprintf(note, sizeof note, "%s; nominal %.0f GB/s from %s",
                    measured > 0 ? "measured device-to-device copy" : "nominal, copy not measurable", nominal,
                    dev.peak_bandwidth_gbs > 0 ? "memory clock x bus width" : "the H100 SXM5 datasheet");
      peak_note = note;
    }
    std::printf(
        "# %s; device: %s; peak %.0f GB/s (%s); cpu threads %d; radius %.2f at unit density; %s order; %s input;"
        " %s lists%s\n",
        choice.note.c_str(), dev.device_count ? dev.name.c_str() : "none", peak, peak_note.c_str(), cpu::threadCount(),
        kRadius, morton ? "Morton" : "bucket", g_shuffle ? "shuffled" : "lattice-order",
        g_storage ? "storage-order" : "original-order", g_fresh_lists ? "; CPU: fresh lists every call" : "");
    std::printf("%-5s %-6s %10s %7s %11s %11s %11s %9s %8s %8s %8s %10s\n", "back", "prec", "n", "nbr/p", "build_ms",
                "query_ms", "total_ms", "ns/p", "B/p", "GB/s", "peak", "target_ms");
    std::vector<Row> rows;
    auto cellFactor = [&](bool on_gpu) { return cell_factor > 0 ? cell_factor : (on_gpu ? 1.0 : 0.5); };
    auto run = [&](bool on_gpu, std::size_t n) {
      const int reps = repeats > 0 ? repeats : (quick ? 3 : (on_gpu ? 10 : 5));
      Row r;
#if INCISION_HAVE_CUDA
      if (on_gpu)
        r = precision == "double" ? runCuda<double>(n, reps, morton, cellFactor(true), peak, profile)
                                  : runCuda<float>(n, reps, morton, cellFactor(true), peak, profile);
#endif
      if (!on_gpu)
        r = precision == "double" ? runCpu<double>(n, reps, morton, cellFactor(false))
                                  : runCpu<float>(n, reps, morton, cellFactor(false));
      r.cell_factor = cellFactor(on_gpu);
      r.precision = precision;
      printRow(r);
      std::fflush(stdout);
      rows.push_back(r);
    };
    for (std::size_t n : sizes(lo, hi, quick)) run(gpu, n);
    if (cpu_max > 0)
      for (std::size_t n : sizes(lo, std::max(lo, cpu_max), quick)) run(false, n);

    if (!csv.empty()) {
      std::ofstream f(csv);
      if (!f) throw InputError(csv, "--csv", "cannot write the file");
      f << "backend,precision,order,input,lists,cell_factor,n,neighbors_per_particle,build_ms,query_ms,total_ms,ns_per_"
           "particle,"
           "bytes_per_particle,achieved_gbs,peak_gbs,peak_fraction,target_ms,total_min_ms,total_max_ms,host_peak_mib,"
           "device_peak_mib\n";
      for (const Row& r : rows)
        f << r.backend << ',' << r.precision << ',' << (morton ? "morton" : "bucket") << ','
          << (g_shuffle ? "shuffled" : "lattice") << ',' << (g_storage ? "storage" : "original") << ',' << r.cell_factor
          << ',' << r.n << ',' << r.neighbours << ',' << r.build_ms << ',' << r.query_ms << ',' << r.total_ms << ','
          << r.total_ms * 1e6 / double(r.n) << ',' << r.bytes << ',' << r.gbs << ','
          << (r.backend == "cuda" ? peak : 0.0) << ',' << r.peak_fraction << ',' << r.target_ms << ',' << r.total_min_ms
          << ',' << r.total_max_ms << ',' << r.host_peak_mib << ',' << r.device_peak_mib << '\n';
    }
    // one-line summary (last line): the largest run of each backend and the 1e6 row when present
    std::string summary = "bench_neighbors " + precision + (g_storage ? " storage-order" : "") + ":";
    for (const std::string b : {"cuda", "cpu"}) {
      const Row* big = nullptr;
      const Row* mega = nullptr;
      for (const Row& r : rows)
        if (r.backend == b) {
          if (!big || r.n > big->n) big = &r;
          if (r.n == 1000000) mega = &r;
        }
      char buf[200];
      if (mega) {
        std::snprintf(buf, sizeof buf, " %s 1e6 %.3f ms (target %.1f);", b.c_str(), mega->total_ms,
                      b == "cuda" ? 0.5 : 300.0);
        summary += buf;
      }
      if (big && big != mega) {
        if (b == "cuda")
          std::snprintf(buf, sizeof buf, " %s %zu %.3f ms, %.0f%% of peak;", b.c_str(), big->n, big->total_ms,
                        100.0 * big->peak_fraction);
        else
          std::snprintf(buf, sizeof buf, " %s %zu %.3f ms, %.1f GB/s modelled;", b.c_str(), big->n, big->total_ms,
                        big->gbs);
        summary += buf;
      }
    }
    std::printf("%s\n", summary.c_str());
  } catch (const InputError& e) {
    std::fprintf(stderr, "bench_neighbors: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_neighbors: %s\n", e.what());
    return 1;
  }
  return 0;
}
