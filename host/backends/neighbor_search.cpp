// Dispatches findNeighbors to the CPU grid search or (when compiled and a device is usable) the CUDA one.
#include "host/backends/neighbor_search.h"

#include <algorithm>
#include <string>

#include "cpu_fallback/neighbor_search_cpu.h"
#include "host/backends/backend_choice.h"
#include "model/input_error.h"
#include "physics/neighbor_grid.h"
#if INCISION_HAVE_CUDA
#include "kernels/neighbor_search_cuda.h"
#endif

namespace inc {
namespace {

// The cell size: the option when given; else, on the CPU, half the largest radius when that grid stays dense
// (at most one cell per bucket, so no hashing), else the largest radius. Half-radius cells visit about
// (2.5 r)^3 of candidates instead of (3 r)^3 (5 x 5 rows of about 5 cells instead of 3 x 3 rows of 3), which
// pays for the CPU's portable scan and is about even for its AVX2 scan on original-order lists; on the GPU
// the longer contiguous runs of radius-sized cells (9 rows instead of 25, loads overlapped) won: 1e6 particles
// 0.57 ms against 0.64 ms on an H100. docs/neighbor-search.md has the measurements. The bounding box is
// computed here for the decision only.
template <typename T>
T chooseCellSize(const std::vector<Vec3<T>>& points, const std::vector<T>& radii, const NeighborSearchOptions& options,
                 bool gpu) {
  for (std::size_t i = 0; i < radii.size(); ++i)
    if (!neighborRadiusValid(radii[i]))
      throw InputError("", radii.size() == 1 ? std::string("radius") : "radii[" + std::to_string(i) + "]",
                       "must be finite and >= 0, got " + std::to_string(double(radii[i])));
  if (options.cell_size > 0.0) return T(options.cell_size);
  T largest = T(0);
  for (T r : radii) largest = r > largest ? r : largest;
  if (!(largest > T(0))) return T(1);
  if (gpu) return largest;
  Vec3<T> lo, hi;
  bool any = false;
  for (const Vec3<T>& x : points) {
    if (!neighborPointFinite(x)) continue;  // the search itself reports it
    if (!any) lo = hi = x;
    any = true;
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], x[a]);
      hi[a] = std::max(hi[a], x[a]);
    }
  }
  if (!any || points.size() > (std::size_t(1) << 30)) return largest;
  const T half = largest / T(2);
  const NeighborGridParams<T> p = makeNeighborGridParams(lo, hi, half, neighborBucketCount(points.size()), 0, true);
  return p.dense ? half : largest;
}
}  // namespace

template <typename T>
NeighborLists findNeighbors(BackendKind backend, const std::vector<Vec3<T>>& points, T radius,
                            const NeighborSearchOptions& options) {
  const BackendChoice choice = resolveBackend(backend);
  const T cell = chooseCellSize(points, std::vector<T>{radius}, options, choice.kind == BackendKind::Cuda);
#if INCISION_HAVE_CUDA
  if (choice.kind == BackendKind::Cuda) {
    cuda::GridNeighborSearch<T> s;
    s.build(points, cell, options.morton_order);
    return s.querySelf(radius).download();
  }
#endif
  return cpu::GridNeighborSearch<T>(points, cell, options.morton_order).querySelf(radius);
}

template <typename T>
NeighborLists findNeighbors(BackendKind backend, const std::vector<Vec3<T>>& queries,
                            const std::vector<Vec3<T>>& points, const std::vector<T>& radii,
                            const NeighborSearchOptions& options) {
  if (radii.size() != 1 && radii.size() != queries.size())
    throw InputError("", "radii",
                     "expected 1 radius or one per query (" + std::to_string(queries.size()) + "), got " +
                         std::to_string(radii.size()));
  const BackendChoice choice = resolveBackend(backend);
  const T cell = chooseCellSize(points, radii, options, choice.kind == BackendKind::Cuda);
#if INCISION_HAVE_CUDA
  if (choice.kind == BackendKind::Cuda) {
    cuda::GridNeighborSearch<T> s;
    s.build(points, cell, options.morton_order);
    cuda::DeviceBuffer<Vec3<T>> q;
    cuda::DeviceBuffer<T> r;
    q.upload(queries);
    r.upload(radii);
    cuda::DeviceNeighborLists out;
    s.query(q.data(), queries.size(), r.data(), radii.size(), out);
    return out.download();
  }
#endif
  return cpu::GridNeighborSearch<T>(points, cell, options.morton_order).query(queries, radii);
}

template NeighborLists findNeighbors<float>(BackendKind, const std::vector<Vec3f>&, float,
                                            const NeighborSearchOptions&);
template NeighborLists findNeighbors<double>(BackendKind, const std::vector<Vec3d>&, double,
                                             const NeighborSearchOptions&);
template NeighborLists findNeighbors<float>(BackendKind, const std::vector<Vec3f>&, const std::vector<Vec3f>&,
                                            const std::vector<float>&, const NeighborSearchOptions&);
template NeighborLists findNeighbors<double>(BackendKind, const std::vector<Vec3d>&, const std::vector<Vec3d>&,
                                             const std::vector<double>&, const NeighborSearchOptions&);

}  // namespace inc
