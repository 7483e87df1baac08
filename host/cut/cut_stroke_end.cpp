// computeStrokeEnd: Algorithm 1 and the caller's model build beside the surface split, then the skin binding.
#include "host/cut/cut_stroke_end.h"

#include <algorithm>
#include <chrono>

#include "base/elapsed_ms.h"
#include "host/assembly/metaball_model.h"
#include "model/input_error.h"

namespace inc {

StrokeEndResult computeStrokeEnd(const StrokeEndInput& in, BackgroundTask& beside,
                                 const std::function<void(const MetaballModel&)>& build) {
  const auto t0 = std::chrono::steady_clock::now();
  StrokeEndResult r;
  r.spheres = in.kept;
  const SweptSurface& swept = in.cuts.back();
  std::vector<const SweptSurface*> cuts{&swept};  // this stroke first, then the earlier ones
  for (std::size_t c = 0; c + 1 < in.cuts.size(); ++c) cuts.push_back(&in.cuts[c]);
  // The split touches only the surface; the re-pack and the build only the spheres: they run side by side.
  beside.runBeside(
      [&] {
        const auto c0 = std::chrono::steady_clock::now();
        r.surface = *in.surface;
        SurfaceSplit s;
        try {
          s = applySurfaceCut(r.surface, swept);
        } catch (const InputError& e) {
          if (!in.interactive) throw;
          s.failure = e.what();  // r.surface is unchanged: applySurfaceCut throws before it writes
        }
        r.split = s.split;
        r.split_failure = s.failure;
        r.surface_components = s.components;  // the split's own output check: no second analysis
        r.split_ms = msSince(c0);
      },
      [&] {
        if (in.repack) {
          const auto c0 = std::chrono::steady_clock::now();
          RepackSettings rs = in.settings;
          rs.earlier_cuts.assign(cuts.begin() + 1, cuts.end());
          r.repack = packNodalPoints(in.points, swept, rs);
          appendRepackedSpheres(r.spheres, r.repack, cuts);
          r.repacked = true;
          r.repack_ms = msSince(c0);
          const auto c1 = std::chrono::steady_clock::now();
          build(r.spheres);
          r.build_ms = msSince(c1);
        }
      });
  const auto c2 = std::chrono::steady_clock::now();
  const int k = std::min<int>(in.skin_k, int(r.spheres.size()));
  r.skin = bindSkinAcrossCuts(r.surface, r.spheres, in.cuts, k, in.file);
  r.bind_ms = msSince(c2);
  r.sphere_components = sphereGraphComponents(r.spheres);
  r.total_ms = msSince(t0);
  return r;
}

}  // namespace inc
