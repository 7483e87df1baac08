// Benchmark: sphere packing time of the liver-like organ, and skinning time per frame (CPU / CUDA) against vertex
// count.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "base/parallel.h"
#include "cpu_fallback/skinning_cpu.h"
#include "host/assembly/metaball_packing.h"
#include "host/assembly/organ_shapes.h"
#include "host/assembly/skin_binding.h"
#include "kernels/device_info.h"
#include "model/input_error.h"
#if INCISION_HAVE_CUDA
#include <cuda_runtime.h>

#include "kernels/cuda_check.h"
#include "kernels/device_buffer.h"
#include "kernels/skinning_cuda.h"
#endif

namespace {

using namespace inc;
using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

struct Row {
  std::string what, backend, precision;
  int vertices = 0, spheres = 0, k = 0;
  double ms_skin = 0.0, ms_skin_normals = 0.0, ms_frame = 0.0;  // frame: rotations + skin + normals
};

// A bending motion of the spheres (rotation about z growing along x), the kind of frame the solver hands over.
template <typename T>
void bendFrame(const MetaballModel& m, int frame, std::vector<Vec3<T>>& c, std::vector<Mat3<T>>& r) {
  c.resize(m.size());
  r.resize(m.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Vec3d p = m.rest_centers[i];
    const double a = 0.002 * frame * p.x / 0.1;
    const Mat3d R = Mat3d::fromRows({std::cos(a), -std::sin(a), 0}, {std::sin(a), std::cos(a), 0}, {0, 0, 1});
    c[i] = Vec3<T>(R * p);
    r[i] = Mat3<T>(R);
  }
}

template <typename T>
Row skinCpu(const SkinArrays<T>& arr, const SphereNeighbourhoods<T>& nb, const MetaballModel& m, int reps) {
  Row row;
  const auto view = arr.view();
  std::vector<Vec3<T>> x(arr.rest_vertices.size()), n(arr.rest_vertices.size()), c;
  std::vector<Mat3<T>> r, est(m.size());
  std::vector<pbd::Quat<T>> q(m.size());
  std::vector<double> t_skin, t_both, t_frame;
  for (int f = 0; f < reps + 2; ++f) {  // two warm-up frames
    bendFrame(m, f, c, r);
    const auto t0 = Clock::now();
    cpu::skinSurfaceCpu(view, c.data(), r.data(), x.data());
    const auto t1 = Clock::now();
    cpu::vertexNormalsCpu(view.vertex_count, x.data(), arr.triangles.data(), arr.tri_offsets.data(),
                          arr.tri_of_vertex.data(), n.data());
    const auto t2 = Clock::now();
    // A whole frame as the runner does it: rotations estimated from the centres (2 warm-started iterations).
    cpu::sphereRotationsCpu(int(m.size()), c.data(), nb.rest_centres.data(), nb.masses.data(), nb.offsets.data(),
                            nb.neighbours.data(), 2, q.data(), est.data());
    cpu::skinSurfaceCpu(view, c.data(), est.data(), x.data());
    cpu::vertexNormalsCpu(view.vertex_count, x.data(), arr.triangles.data(), arr.tri_offsets.data(),
                          arr.tri_of_vertex.data(), n.data());
    const auto t3 = Clock::now();
    if (f >= 2) {
      t_skin.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      t_both.push_back(std::chrono::duration<double, std::milli>(t2 - t0).count());
      t_frame.push_back(std::chrono::duration<double, std::milli>(t3 - t2).count());
    }
  }
  row.ms_skin = median(t_skin);
  row.ms_skin_normals = median(t_both);
  row.ms_frame = median(t_frame);
  return row;
}

#if INCISION_HAVE_CUDA
template <typename T>
Row skinCuda(const SkinArrays<T>& arr, const SphereNeighbourhoods<T>& nb, const MetaballModel& m, int reps) {
  Row row;
  cuda::SkinningCuda<T> gpu;
  gpu.upload(arr.view(), int(arr.rest_centres.size()), arr.triangles, arr.tri_offsets, arr.tri_of_vertex);
  gpu.uploadNeighbourhoods(nb.offsets, nb.neighbours, nb.masses);
  cuda::DeviceBuffer<Vec3<T>> dc;
  cuda::DeviceBuffer<Mat3<T>> dr;
  std::vector<Vec3<T>> c;
  std::vector<Mat3<T>> r;
  bendFrame(m, 7, c, r);
  dc.upload(c);
  dr.upload(r);
  cudaEvent_t e0, e1, e2, e3;
  INC_CUDA(cudaEventCreate(&e0));
  INC_CUDA(cudaEventCreate(&e1));
  INC_CUDA(cudaEventCreate(&e2));
  INC_CUDA(cudaEventCreate(&e3));
  std::vector<double> t_skin, t_both, t_frame;
  for (int f = 0; f < reps + 3; ++f) {  // three warm-up frames
    INC_CUDA(cudaEventRecord(e0));
    gpu.deformDevice(dc.data(), dr.data());
    INC_CUDA(cudaEventRecord(e1));
    gpu.normalsDevice();
    INC_CUDA(cudaEventRecord(e2));
    gpu.estimateRotationsDevice(dc.data(), 2);
    gpu.deformDevice(dc.data(), gpu.rotations());
    gpu.normalsDevice();
    INC_CUDA(cudaEventRecord(e3));
    INC_CUDA(cudaEventSynchronize(e3));  // timing needs the events' times on the host
    float a = 0.0f, b = 0.0f, c3 = 0.0f;
    INC_CUDA(cudaEventElapsedTime(&a, e0, e1));
    INC_CUDA(cudaEventElapsedTime(&b, e0, e2));
    INC_CUDA(cudaEventElapsedTime(&c3, e2, e3));
    if (f >= 3) {
      t_skin.push_back(a);
      t_both.push_back(b);
      t_frame.push_back(c3);
    }
  }
  INC_CUDA(cudaEventDestroy(e0));
  INC_CUDA(cudaEventDestroy(e1));
  INC_CUDA(cudaEventDestroy(e2));
  INC_CUDA(cudaEventDestroy(e3));
  row.ms_skin = median(t_skin);
  row.ms_skin_normals = median(t_both);
  row.ms_frame = median(t_frame);
  return row;
}
#endif

template <typename T>
int run(const std::string& backend, const std::string& precision, int min_v, int max_v, int cpu_max, int k,
        const PackingOptions& popt, bool quick, int repeats, const std::string& csv) {
  [[maybe_unused]] const bool want_gpu = backend != "cpu";  // read only with CUDA
  bool have_gpu = false;
#if INCISION_HAVE_CUDA
  have_gpu = want_gpu && cuda::queryDevices().device_count > 0;
#endif
  if (backend == "cuda" && !have_gpu) {
    std::printf("no CUDA device: running the CPU only\n");
  }
  // 1. Packing of the reference organ (the paper's Table 1 liver: 8128 vertices, 570 spheres, 1884 s).
  const TriangleMesh ref = makeLiverLikeMesh({8000, 0.2, 0});
  std::vector<double> pack_s;
  PackedOrgan pack;
  for (int rep = 0; rep < (quick ? 1 : 3); ++rep) {
    pack = packOrgan(ref, popt);
    pack_s.push_back(pack.report.seconds);
  }
  const PackReport& pr = pack.report;
  std::printf(
      "packing: liver-like %zu vertices -> %d spheres, %d links, coverage %.4f, surface dev mean %.2e max %.2e m, "
      "protrusion %.2e m, %.3f s (median of %zu, %d threads)\n",
      ref.vertices.size(), pr.spheres, pr.links, pr.coverage, pr.surface_mean, pr.surface_max, pr.max_protrusion,
      median(pack_s), pack_s.size(), cpu::threadCount());

  // 1b. Packing time against the sphere count (samples grow with it: 80 per sphere, at least the option's).
  struct PackRow {
    int target, spheres, samples;
    double seconds, coverage, surface_max;
  };
  std::vector<PackRow> pack_rows;
  if (!quick) {
    std::printf("%-10s %8s %8s %9s %10s %10s %14s\n", "what", "target", "spheres", "samples", "seconds", "coverage",
                "surf max (m)");
    for (int target : {150, 550, 2000, 5000}) {
      PackingOptions o = popt;
      o.target_spheres = target;
      o.samples = std::max(popt.samples, 80 * target);
      const PackedOrgan pk = packOrgan(ref, o);
      pack_rows.push_back(
          {target, pk.report.spheres, o.samples, pk.report.seconds, pk.report.coverage, pk.report.surface_max});
      std::printf("%-10s %8d %8d %9d %10.3f %10.4f %14.3e\n", "pack", target, pk.report.spheres, o.samples,
                  pk.report.seconds, pk.report.coverage, pk.report.surface_max);
      std::fflush(stdout);
    }
  }

  // 2. Skinning per frame against vertex count (same shape, same spheres).
  std::vector<int> sizes;
  for (int v : {1000, 8000, 30000, 100000, 300000, 1000000, 3000000})
    if (v >= min_v && v <= max_v) sizes.push_back(v);
  if (quick && sizes.size() > 3)
    sizes = {sizes.front(), 8000 >= min_v && 8000 <= max_v ? 8000 : sizes[1], sizes.back()};
  const int reps = repeats > 0 ? repeats : (quick ? 5 : 50);
  std::vector<Row> rows;
  std::printf("%-10s %-6s %-7s %10s %8s %3s %12s %16s %22s\n", "what", "backend", "prec", "vertices", "spheres", "k",
              "skin ms", "skin+normals ms", "rot+skin+normals ms");
  for (int target : sizes) {
    const TriangleMesh mesh = makeLiverLikeMesh({target, 0.2, 0});
    const SkinArrays<T> arr = skinArrays<T>(bindSkin(mesh, pack.model, k));
    const SphereNeighbourhoods<T> nb = sphereNeighbourhoods<T>(pack.model);
    auto emit = [&](Row row, const char* be) {
      row.what = "skin";
      row.backend = be;
      row.precision = precision;
      row.vertices = int(mesh.vertices.size());
      row.spheres = int(pack.model.size());
      row.k = k;
      std::printf("%-10s %-6s %-7s %10d %8d %3d %12.4f %16.4f %22.4f\n", row.what.c_str(), be, precision.c_str(),
                  row.vertices, row.spheres, k, row.ms_skin, row.ms_skin_normals, row.ms_frame);
      std::fflush(stdout);
      rows.push_back(row);
    };
    if (int(mesh.vertices.size()) <= cpu_max) emit(skinCpu(arr, nb, pack.model, reps), "cpu");
#if INCISION_HAVE_CUDA
    if (have_gpu) emit(skinCuda(arr, nb, pack.model, reps), "cuda");
#endif
  }
  if (!csv.empty()) {
    std::ofstream f(csv);
    if (!f) throw InputError(csv, "--csv", "cannot write the file");
    f << "what,backend,precision,vertices,spheres,k,ms_skin,ms_skin_normals,ms_frame,pack_s,coverage\n";
    f << "pack,cpu," << precision << "," << ref.vertices.size() << "," << pr.spheres << ",0,0,0,0," << median(pack_s)
      << "," << pr.coverage << "\n";
    for (const auto& r : pack_rows)
      f << "pack,cpu," << precision << "," << ref.vertices.size() << "," << r.spheres << ",0,0,0,0," << r.seconds << ","
        << r.coverage << "\n";
    for (const auto& r : rows)
      f << r.what << "," << r.backend << "," << r.precision << "," << r.vertices << "," << r.spheres << "," << r.k
        << "," << r.ms_skin << "," << r.ms_skin_normals << "," << r.ms_frame << ",,\n";
  }
  // One-line summary (last line): packing, and skinning of the reference-sized surface per backend.
  std::string summary = "bench_packing " + precision + ": pack " + std::to_string(pr.spheres) + " spheres " +
                        std::to_string(median(pack_s)).substr(0, 6) + " s coverage " +
                        std::to_string(pr.coverage).substr(0, 6);
  for (const auto& r : rows)
    if (r.vertices >= 7000 && r.vertices <= 9000) {
      char buf[128];
      std::snprintf(buf, sizeof buf, "; rot+skin+normals %d v %s %.4f ms", r.vertices, r.backend.c_str(), r.ms_frame);
      summary += buf;
    }
  std::printf("%s\n", summary.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Sphere packing and skinning benchmark"};
  std::string backend = "auto", precision = "float", csv;
  int min_v = 1000, max_v = 1000000, cpu_max = 1000000, k = 4, repeats = 0;
  bool quick = false;
  PackingOptions popt;
  app.add_option("--backend", backend, "cpu, cuda or auto")->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  app.add_option("--precision", precision, "float or double")->check(CLI::IsMember({"float", "double"}));
  app.add_option("--min", min_v, "smallest surface vertex count");
  app.add_option("--max", max_v, "largest surface vertex count");
  app.add_option("--cpu-max", cpu_max, "largest vertex count run on the CPU");
  app.add_option("--k", k, "spheres per vertex");
  app.add_option("--spheres", popt.target_spheres, "target sphere count of the packing");
  app.add_option("--samples", popt.samples, "interior samples of the packing");
  app.add_option("--repeats", repeats, "timed frames per size (0: 50, quick 5)");
  app.add_option("--csv", csv, "write the rows as CSV here");
  app.add_flag("--quick", quick, "a short run: three sizes, few frames, one packing");
  CLI11_PARSE(app, argc, argv);
  try {
    if (quick) popt.samples = std::min(popt.samples, 15000);
    if (precision == "double")
      return run<double>(backend, precision, min_v, max_v, cpu_max, k, popt, quick, repeats, csv);
    return run<float>(backend, precision, min_v, max_v, cpu_max, k, popt, quick, repeats, csv);
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitBadInput;
  }
}
