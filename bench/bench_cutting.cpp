// Cut update time vs organ size: deforming / cutting / cut-applying frames of DissectionSimulation and the cut stages.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "host/backend.h"
#include "host/cut_mesh.h"
#include "host/cut_nodal_points.h"
#include "host/dissection_simulation.h"
#include "host/input_error.h"
#include "host/metaball_simulation.h"
#if INCISION_HAVE_CUDA
#include "kernels/cut_cuda.h"
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

struct Row {
  std::string backend;
  int target = 0, spheres = 0, cut_spheres = 0, nodal_points = 0, spheres_added = 0, vertices = 0;
  double ms_deform = 0, ms_cutting = 0, ms_apply_frame = 0, ms_after = 0;
  double ms_find_cpu = 0, ms_find_gpu = -1, ms_nodes = 0, ms_visibility = 0, ms_repack = 0, ms_split = 0;
};

// The liver_cut scene (ellipsoid 18 x 12 x 7 cm) at the lattice spacing that gives about `target` spheres.
Scene liverScene(int target, double cut_length_fraction) {
  Scene s;
  s.file = "<bench:liver_cut>";
  s.geometry.kind = GeometrySpec::Kind::Ellipsoid;
  s.geometry.radii = Vec3d(0.09, 0.06, 0.035);
  const double volume = 4.0 / 3.0 * 3.141592653589793 * 0.09 * 0.06 * 0.035;
  s.geometry.spacing = std::cbrt(volume / target);
  s.material.youngs_modulus = 5e3;
  s.material.damping = 4.0;
  s.models.pbd_metaballs = true;
  s.models.cutting = true;
  s.solver.substeps = 4;
  s.pbd.iterations = 10;
  s.pbd.solver = "gauss_seidel";
  s.fixed = {{Vec3d(-0.1, -0.07, -0.04), Vec3d(0.1, 0.07, -0.02)}};
  ToolSpec t;
  t.name = "scalpel";
  t.kind = "scalpel";
  t.length = 0.1;
  const double x1 = -0.12 + 0.24 * cut_length_fraction;
  t.path = {{0.1, Vec3d(-0.12, 0.004, 0), Vec3d(0, 0, 1)}, {0.6, Vec3d(x1, 0.004, 0), Vec3d(0, 0, 1)}};
  s.tools = {t};
  return s;
}

Row runCase(BackendKind backend, int target, int reps) {
  Row r;
  r.backend = backendName(backend);
  r.target = target;
  const Scene scene = liverScene(target, 1.0);
  const double dt = 1.0 / 60.0;
  // Frames: 0.1 s deforming, 0.5 s cutting, the apply frame, 0.2 s after.
  auto sim = makeDissectionSimulation(scene, backend, Precision::Float32);
  r.spheres = int(sim->particleCount());
  std::vector<double> deform, cutting, after;
  double t = 0;
  bool applied = false;
  for (int f = 0; f < 60; ++f) {
    const auto c0 = Clock::now();
    FrameReport rep = sim->advance(dt);
    const double ms = msSince(c0);
    t += dt;
    if (!rep.finite) throw InputError("bench_cutting", "frame", "non-finite state at frame " + std::to_string(f));
    if (rep.counters["cuts_applied"] > 0 && !applied) {
      applied = true;
      r.ms_apply_frame = ms;
      r.nodal_points = int(rep.counters["nodal_points_last_cut"]);
      r.spheres_added = int(rep.counters["spheres_added_last_cut"]);
    } else if (applied) {
      after.push_back(ms);
    } else if (t > 0.1 + dt) {
      cutting.push_back(ms);
    } else {
      deform.push_back(ms);
    }
    if (applied && after.size() >= 12) break;
  }
  r.ms_deform = median(deform);
  r.ms_cutting = median(cutting);
  r.ms_after = median(after);
  TriangleMesh surf;
  sim->currentSurface(surf);
  r.vertices = int(surf.vertices.size());

  // Stage breakdown on the rest model (median of reps).
  const MetaballModel mb = buildSceneMetaballs(scene);
  const SweptSurface swept = sweepSurface({{Vec3d(-0.12, 0.004, -0.05), Vec3d(-0.12, 0.004, 0.05)},
                                           {Vec3d(0.12, 0.004, -0.05), Vec3d(0.12, 0.004, 0.05)}});
  const TriangleMesh surface = sceneSurfaceMesh(scene);
  std::vector<double> find, nodes, vis, repack, split, find_gpu;
  for (int k = 0; k < reps; ++k) {
    auto c0 = Clock::now();
    const auto ids = findCutSpheres(swept, mb.rest_centers, mb.rest_radii);
    find.push_back(msSince(c0));
    r.cut_spheres = int(ids.size());
    c0 = Clock::now();
    SphereCutResult cr = cutSpheres(mb, swept);
    nodes.push_back(msSince(c0));
    c0 = Clock::now();
    const NeighborLists nl = visibleNodalNeighbours(cr.points, 2.5 * cr.points.spacing, swept);
    vis.push_back(msSince(c0));
    c0 = Clock::now();
    repackSpheres(cr.spheres, cr.points, swept);
    repack.push_back(msSince(c0));
    c0 = Clock::now();
    const CutMeshResult m = splitMeshByPlane(surface, Vec3d(0, 0.004, 0), Vec3d(0, -1, 0));
    split.push_back(msSince(c0));
#if INCISION_HAVE_CUDA
    if (backend == BackendKind::Cuda) {
      c0 = Clock::now();
      const auto mask = cuda::cutSphereMaskCuda(swept.vertices, swept.triangles, mb.rest_centers, mb.rest_radii);
      find_gpu.push_back(msSince(c0));  // includes upload and download (what a cut event costs)
    }
#endif
  }
  r.ms_find_cpu = median(find);
  r.ms_nodes = median(nodes);
  r.ms_visibility = median(vis);
  r.ms_repack = median(repack);
  r.ms_split = median(split);
  if (!find_gpu.empty()) r.ms_find_gpu = median(find_gpu);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Cutting: frame time deforming / cutting / applying the cut vs organ size, and the cut stages"};
  std::string backend_text = "auto", csv, sizes_text = "500,2000,8000,32000";
  int max_spheres = 32000, cpu_max = 8000, reps = 5;
  bool quick = false;
  app.add_option("--backend", backend_text, "cpu | cuda | auto | both");
  app.add_option("--sizes", sizes_text, "target sphere counts, comma separated");
  app.add_option("--max", max_spheres, "skip sizes above this many spheres");
  app.add_option("--cpu-max", cpu_max, "skip CPU rows above this many spheres");
  app.add_option("--reps", reps, "repetitions of each stage timing (median)");
  app.add_option("--csv", csv, "write the rows as CSV here");
  app.add_flag("--quick", quick, "a short run: sizes 500,2000, 3 reps");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (quick) {
      sizes_text = "500,2000";
      reps = 3;
    }
    std::vector<int> sizes;
    for (std::size_t a = 0; a < sizes_text.size();) {
      const std::size_t b = std::min(sizes_text.find(',', a), sizes_text.size());
      sizes.push_back(std::stoi(sizes_text.substr(a, b - a)));
      a = b + 1;
    }
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
    std::printf("%-5s %7s %7s %6s %7s %6s %7s | %8s %8s %8s %8s | %8s %8s %8s %8s %8s %8s\n", "back", "target",
                "spheres", "cut", "nodes", "added", "verts", "deform", "cutting", "apply", "after", "find", "findGPU",
                "nodes", "visib", "repack", "split");
    for (BackendKind b : backends) {
      if (b == BackendKind::Cuda && !have_gpu) continue;
      for (int n : sizes) {
        if (n > max_spheres || (b == BackendKind::Cpu && n > cpu_max)) continue;
        const Row r = runCase(b, n, std::max(1, reps));
        rows.push_back(r);
        std::printf("%-5s %7d %7d %6d %7d %6d %7d | %8.3f %8.3f %8.3f %8.3f | %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f\n",
                    r.backend.c_str(), r.target, r.spheres, r.cut_spheres, r.nodal_points, r.spheres_added, r.vertices,
                    r.ms_deform, r.ms_cutting, r.ms_apply_frame, r.ms_after, r.ms_find_cpu, r.ms_find_gpu, r.ms_nodes,
                    r.ms_visibility, r.ms_repack, r.ms_split);
        std::fflush(stdout);
      }
    }
    if (!csv.empty()) {
      std::ofstream f(csv);
      if (!f) throw InputError(csv, "--csv", "cannot write");
      f << "backend,target,spheres,cut_spheres,nodal_points,spheres_added,vertices,ms_deform,ms_cutting,ms_apply_frame,"
           "ms_after,ms_find_cpu,ms_find_gpu,ms_nodes,ms_visibility,ms_repack,ms_split\n";
      for (const Row& r : rows)
        f << r.backend << ',' << r.target << ',' << r.spheres << ',' << r.cut_spheres << ',' << r.nodal_points << ','
          << r.spheres_added << ',' << r.vertices << ',' << r.ms_deform << ',' << r.ms_cutting << ','
          << r.ms_apply_frame << ',' << r.ms_after << ',' << r.ms_find_cpu << ',' << r.ms_find_gpu << ','
          << r.ms_nodes << ',' << r.ms_visibility << ',' << r.ms_repack << ',' << r.ms_split << '\n';
    }
    if (rows.empty()) {
      std::printf("bench_cutting: no rows (sizes above the limits or no device)\n");
      return 0;
    }
    const Row& last = rows.back();
    std::printf("bench_cutting: %s %d spheres: deform %.3f ms, cutting %.3f ms, cut apply frame %.3f ms per frame\n",
                last.backend.c_str(), last.spheres, last.ms_deform, last.ms_cutting, last.ms_apply_frame);
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
