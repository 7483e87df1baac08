// Benchmark: time of the surface split (splitSurfaceBySweep) on an organ mesh for planar, curved and partial cuts.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <string>
#include <vector>

#include "host/assembly/organ_shapes.h"
#include "host/cut/cut_mesh.h"
#include "host/cut/cut_surface_split.h"
#include "model/input_error.h"

namespace {

using namespace inc;
using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
// Process CPU time (ms): the split is single-threaded, so on a machine shared with other jobs this is closer to
// the unloaded wall time than the wall clock.
double cpuMs() { return 1000.0 * double(std::clock()) / CLOCKS_PER_SEC; }

// A blade parallel to z, longer than the mesh is tall, whose centre runs along the circle of radius r about
// (cx, cy) from angle a0 to a1 in `steps` strips (one strip per frame of a scripted cut).
SweptSurface arc(double cx, double cy, double r, double a0, double a1, int steps, double z0, double z1) {
  std::vector<BladePose> poses;
  for (int k = 0; k <= steps; ++k) {
    const double a = a0 + (a1 - a0) * k / steps;
    const Vec3d c(cx + r * std::cos(a), cy + r * std::sin(a), 0.0);
    poses.push_back({c + Vec3d(0, 0, z0), c + Vec3d(0, 0, z1)});
  }
  return sweepSurface(poses);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Cut surface: time of the surface split along a swept surface (planar / curved / partial)"};
  std::string mesh_path = "../shared/organs/liver-smooth.obj";
  int reps = 5, steps = 30;
  app.add_option("--mesh", mesh_path, "closed organ surface (OBJ/PLY/STL); a liver-like mesh is generated when absent");
  app.add_option("--reps", reps, "repetitions per case (median)");
  app.add_option("--steps", steps, "strips of the swept surface (frames of the scripted cut)");
  CLI11_PARSE(app, argc, argv);
  try {
    TriangleMesh mesh;
    if (std::ifstream(mesh_path).good()) {
      mesh = loadMesh(mesh_path);
      requireClosedMesh(mesh, mesh_path, "mesh");
    } else {
      std::printf("%s not found: using the generated liver-like mesh\n", mesh_path.c_str());
      mesh_path = "liver-like (generated)";
      LiverLikeOptions o;
      o.target_vertices = 2200;
      mesh = makeLiverLikeMesh(o);
    }
    const MeshReport rep = analyzeMesh(mesh);
    const Vec3d lo = rep.bbox_min, hi = rep.bbox_max, c = (lo + hi) * 0.5, e = hi - lo;
    const double W = std::max(e.x, e.y), z0 = lo.z - 0.2 * e.z, z1 = hi.z + 0.2 * e.z;
    // Arcs about a centre 1.5 W to the -x side, radius reaching 0.1 W past the middle: the blade crosses the
    // organ along y. Planar: the same blade on a straight line x = const.
    const double R = 1.5 * W + 0.1 * W, cx = c.x - 1.5 * W, span = std::asin(std::min(1.0, 0.75 * W / R));
    struct Case {
      const char* name;
      SweptSurface sweep;
    };
    std::vector<BladePose> line;
    for (int k = 0; k <= steps; ++k) {
      const double y = lo.y - 0.1 * e.y + 1.2 * e.y * k / steps;
      line.push_back({Vec3d(c.x + 0.013 * W, y, z0), Vec3d(c.x + 0.013 * W, y, z1)});
    }
    const Case cases[] = {{"planar through", sweepSurface(line)},
                          {"arc through", arc(cx, c.y, R, -span, span, steps, z0, z1)},
                          {"arc partial", arc(cx, c.y, R, -span, 0.1 * span, steps, z0, z1)}};
    std::printf("mesh %s: %d vertices, %d triangles, size %.3g x %.3g x %.3g\n", mesh_path.c_str(), rep.vertex_count,
                rep.triangle_count, e.x, e.y, e.z);
    // "checked cpu ms": the same split of a mesh that is a split's own output (SurfaceSplitOptions::input_checked, as
    // the second and later cuts of a dissection are), without the input check.
    std::printf("%-16s %9s %9s %6s %6s %8s %10s %8s %8s %10s %10s\n", "case", "tris out", "crossings", "front", "walls",
                "pieces", "split ms", "cpu ms", "checked", "min wall", "min piece");
    for (const Case& k : cases) {
      std::vector<double> ms, cpu, cpu_checked;
      SurfaceSplit r;
      SurfaceSplitOptions checked;
      checked.input_checked = true;
      for (int i = 0; i < reps; ++i) {
        const auto t0 = Clock::now();
        double c0 = cpuMs();
        r = splitSurfaceBySweep(mesh, k.sweep);
        cpu.push_back(cpuMs() - c0);
        ms.push_back(msSince(t0));
        c0 = cpuMs();
        splitSurfaceBySweep(mesh, k.sweep, checked);
        cpu_checked.push_back(cpuMs() - c0);
      }
      std::printf("%-16s %9zu %9d %6d %6d %8d %10.2f %8.2f %8.2f %9.1f° %9.1f°\n", k.name, r.mesh.triangles.size(),
                  r.crossings, r.front_points + r.pierce_points, r.wall_triangles, r.components, median(ms),
                  median(cpu), median(cpu_checked), r.min_wall_angle_deg, r.min_split_angle_deg);
    }
    // The previous planar-only split (ear-clipped caps) on the same plane, for comparison.
    std::vector<double> ms;
    for (int i = 0; i < reps; ++i) {
      const auto t0 = Clock::now();
      const CutMeshResult m = splitMeshByPlane(mesh, Vec3d(c.x + 0.013 * W, 0, 0), Vec3d(-1, 0, 0));
      ms.push_back(msSince(t0));
    }
    std::printf("%-16s %58.2f  (splitMeshByPlane, ear-clipped caps: the planar-only split it replaces)\n",
                "planar (old)", median(ms));
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
