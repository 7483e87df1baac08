// Per-frame cost and memory of each model a scene adds (MLS, PBD, both, + tearing) on the CPU and CUDA backends.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "host/app/runner.h"
#include "host/backends/backend_choice.h"
#include "host/scene/embedded_scenes.h"
#include "host/scene/scene_compile.h"
#include "host/scene/scene_loader.h"
#include "model/backend.h"
#include "model/input_error.h"

using namespace inc;

namespace {

struct Row {
  std::string backend, models;
  std::size_t particles = 0;
  double ms_median = 0, ms_min = 0, ms_max = 0, host_mib = 0, device_mib = 0;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

Row measure(const Scene& s, BackendKind be, int frames) {
  Row r;
  r.backend = backendName(be);
  auto models = createSceneModels(compileScene(s), be);
  for (const auto& m : models) {
    r.models += (r.models.empty() ? "" : "+") + m->name();
    r.particles += m->particleCount();
  }
  std::vector<double> ms;
  for (int f = -1; f < frames; ++f) {  // frame -1: warm-up (neighbour build, first allocations)
    const auto t0 = std::chrono::steady_clock::now();
    for (auto& m : models) m->advance(s.solver.frame_dt);  // advance() returns after its report: device synced
    const auto t1 = std::chrono::steady_clock::now();
    if (f >= 0) ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  r.ms_median = median(ms);
  r.ms_min = *std::min_element(ms.begin(), ms.end());
  r.ms_max = *std::max_element(ms.begin(), ms.end());
  for (const auto& m : models) {
    const MemoryReport mr = m->memory();
    r.host_mib += double(mr.host_bytes) / 1048576.0;
    r.device_mib += double(mr.device_bytes) / 1048576.0;
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_models: per-frame cost and memory of each model added to the beam scene"};
  std::string backend = "auto", csv;
  double spacing = 0.004;
  int frames = 10;
  bool quick = false;
  app.add_option("--backend", backend, "cpu | cuda | auto (CUDA when usable) | both");
  app.add_option("--spacing", spacing, "Particle spacing of the beam (m); the CPU default 4 mm = 500 particles");
  app.add_option("--frames", frames, "Timed frames per configuration (after one warm-up frame)");
  app.add_option("--csv", csv, "CSV output");
  app.add_flag("--quick", quick, "Two frames at 6 mm: checks that it runs");
  CLI11_PARSE(app, argc, argv);
  try {
    if (quick) {
      frames = 2;
      spacing = std::max(spacing, 0.006);
    }
    if (!(spacing > 0.0) || frames < 1) throw InputError("", "--spacing/--frames", "must be positive");
    std::vector<BackendKind> backends;
    if (backend == "both") {
      backends.push_back(BackendKind::Cpu);
#if INCISION_HAVE_CUDA
      if (resolveBackend(BackendKind::Auto).kind == BackendKind::Cuda) backends.push_back(BackendKind::Cuda);
#endif
    } else {
      backends.push_back(resolveBackend(parseBackend(backend)).kind);
    }
    Scene base = parseScene(findEmbeddedScene("beam")->json, "<embedded:beam>", ".");
    base.geometry.spacing = spacing;
    struct Combo {
      bool mls, pbd, tearing;
    };
    const Combo combos[] = {{true, false, false}, {false, true, false}, {true, true, false}, {true, true, true}};
    std::vector<Row> rows;
    std::printf("%-8s %-36s %10s %10s %10s %10s %11s %11s\n", "backend", "models", "particles", "ms/frame", "min",
                "max", "host MiB", "device MiB");
    for (BackendKind be : backends)
      for (const Combo& c : combos) {
        Scene s = base;
        s.models.mls = c.mls;
        s.models.pbd_metaballs = c.pbd;
        s.models.tearing = c.tearing;
        const Row r = measure(s, be, frames);
        std::printf("%-8s %-36s %10zu %10.3f %10.3f %10.3f %11.2f %11.2f\n", r.backend.c_str(), r.models.c_str(),
                    r.particles, r.ms_median, r.ms_min, r.ms_max, r.host_mib, r.device_mib);
        rows.push_back(r);
      }
    if (!csv.empty()) {
      std::ofstream f(csv);
      f << "backend,models,particles,ms_per_frame_median,ms_min,ms_max,host_mib,device_mib\n";
      for (const Row& r : rows)
        f << r.backend << ',' << r.models << ',' << r.particles << ',' << r.ms_median << ',' << r.ms_min << ','
          << r.ms_max << ',' << r.host_mib << ',' << r.device_mib << '\n';
      if (!f) throw InputError(csv, "--csv", "cannot write the file");
    }
    // Summary: the cost each model adds on the last backend (both-minus-one differences).
    const std::size_t k = rows.size() - 4;
    std::printf(
        "bench_models: %s: mls %.3f ms, pbd %.3f ms, mls+pbd %.3f ms, +tearing %.3f ms per frame; memory "
        "mls %.2f, pbd %.2f, +tearing %.2f MiB\n",
        rows[k].backend.c_str(), rows[k].ms_median, rows[k + 1].ms_median, rows[k + 2].ms_median, rows[k + 3].ms_median,
        rows[k].host_mib + rows[k].device_mib, rows[k + 1].host_mib + rows[k + 1].device_mib,
        rows[k + 3].host_mib + rows[k + 3].device_mib - rows[k + 2].host_mib - rows[k + 2].device_mib);
  } catch (const InputError& e) {
    std::fprintf(stderr, "bench_models: %s\n", e.what());
    return 2;
  }
  return 0;
}
