// CUDA cut tests: sphere/swept-surface overlap and neighbour-pair crossing, one thread per element.
#include "kernels/cut_cuda.h"

#include "kernels/cuda_check.h"
#include "kernels/device_buffer.h"
#include "physics/cut_geometry.h"

namespace inc::cuda {

namespace {

__global__ void sphereMaskKernel(const Vec3d* sv, const int* st, int nt, const Vec3d* c, const double* r, int n,
                                 std::uint8_t* out) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  std::uint8_t hit = 0;
  for (int t = 0; t < nt && !hit; ++t)
    hit = cut::sphereTouchesTriangle(c[i], r[i], sv[st[3 * t]], sv[st[3 * t + 1]], sv[st[3 * t + 2]]) ? 1 : 0;
  out[i] = hit;
}

// The query of entry k is found by binary search in offsets (gather, no per-query loop imbalance).
__global__ void pairMaskKernel(const Vec3d* sv, const int* st, int nt, const Vec3d* x, const std::int64_t* offsets,
                               int queries, const std::int32_t* idx, std::int64_t entries, std::uint8_t* out) {
  const std::int64_t k = std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (k >= entries) return;
  int lo = 0, hi = queries - 1;  // largest q with offsets[q] <= k
  while (lo < hi) {
    const int mid = (lo + hi + 1) / 2;
    if (offsets[mid] <= k)
      lo = mid;
    else
      hi = mid - 1;
  }
  const Vec3d p = x[lo], q = x[idx[k]];
  std::uint8_t hit = 0;
  for (int t = 0; t < nt && !hit; ++t)
    hit = cut::segmentCrossesTriangle(p, q, sv[st[3 * t]], sv[st[3 * t + 1]], sv[st[3 * t + 2]]) ? 1 : 0;
  out[k] = hit;
}

std::vector<int> flatten(const std::vector<std::array<int, 3>>& tris) {
  std::vector<int> f;
  f.reserve(tris.size() * 3);
  for (const auto& t : tris) f.insert(f.end(), t.begin(), t.end());
  return f;
}

}  // namespace

std::vector<std::uint8_t> cutSphereMaskCuda(const std::vector<Vec3d>& swept_vertices,
                                            const std::vector<std::array<int, 3>>& swept_triangles,
                                            const std::vector<Vec3d>& centres, const std::vector<double>& radii) {
  const int n = int(centres.size());
  if (n == 0) return {};
  DeviceBuffer<Vec3d> sv, c;
  DeviceBuffer<int> st;
  DeviceBuffer<double> r;
  DeviceBuffer<std::uint8_t> out{static_cast<std::size_t>(n)};
  sv.upload(swept_vertices);
  st.upload(flatten(swept_triangles));
  c.upload(centres);
  r.upload(radii);
  sphereMaskKernel<<<(n + 127) / 128, 128>>>(sv.data(), st.data(), int(swept_triangles.size()), c.data(), r.data(), n,
                                             out.data());
  INC_CUDA_LAUNCH("sphereMaskKernel");
  return out.download();  // the mask decides a topology change on the host
}

std::vector<std::uint8_t> crossingPairMaskCuda(const std::vector<Vec3d>& swept_vertices,
                                               const std::vector<std::array<int, 3>>& swept_triangles,
                                               const std::vector<Vec3d>& positions,
                                               const std::vector<std::int64_t>& offsets,
                                               const std::vector<std::int32_t>& indices) {
  const std::int64_t entries = std::int64_t(indices.size());
  if (entries == 0 || offsets.size() < 2) return std::vector<std::uint8_t>(indices.size(), 0);
  DeviceBuffer<Vec3d> sv, x;
  DeviceBuffer<int> st;
  DeviceBuffer<std::int64_t> off;
  DeviceBuffer<std::int32_t> idx;
  DeviceBuffer<std::uint8_t> out{static_cast<std::size_t>(entries)};
  sv.upload(swept_vertices);
  st.upload(flatten(swept_triangles));
  x.upload(positions);
  off.upload(offsets);
  idx.upload(indices);
  const unsigned blocks = unsigned((entries + 127) / 128);
  pairMaskKernel<<<blocks, 128>>>(sv.data(), st.data(), int(swept_triangles.size()), x.data(), off.data(),
                                  int(offsets.size() - 1), idx.data(), entries, out.data());
  INC_CUDA_LAUNCH("pairMaskKernel");
  return out.download();  // the mask rebuilds the CSR lists on the host
}

}  // namespace inc::cuda
