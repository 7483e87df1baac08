// GPU skinning: CPU == GPU (positions and normals) for float and double, rest and rigid-motion exactness on the device.
#if INCISION_HAVE_CUDA
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "cpu_fallback/skinning_cpu.h"
#include "host/assembly/metaball_packing.h"
#include "host/assembly/organ_shapes.h"
#include "host/assembly/skin_binding.h"
#include "kernels/device_buffer.h"
#include "kernels/device_info.h"
#include "kernels/skinning_cuda.h"

namespace inc {
namespace {

struct Fixture {
  TriangleMesh mesh = makeLiverLikeMesh({8000, 0.2, 0});
  PackedOrgan pack;
  SkinBinding binding;
  Fixture() {
    PackingOptions o;
    o.samples = 10000;
    pack = packOrgan(mesh, o);
    binding = bindSkin(mesh, pack.model, 4);
  }
};
const Fixture& fixture() {
  static const Fixture f;
  return f;
}

// A non-rigid motion: every sphere translated by a smooth field and rotated by its own angle (twist about x).
template <typename T>
void twist(const MetaballModel& m, std::vector<Vec3<T>>& centres, std::vector<Mat3<T>>& rots, double amount) {
  centres.clear();
  rots.clear();
  for (const auto& c : m.rest_centers) {
    const double a = amount * c.x / 0.1;  // radians, grows along the organ
    const double ca = std::cos(a), sa = std::sin(a);
    const Mat3d R = Mat3d::fromRows({1, 0, 0}, {0, ca, -sa}, {0, sa, ca});
    centres.push_back(Vec3<T>(R * c + Vec3d{0.0, 0.01 * c.x, 0.0}));
    rots.push_back(Mat3<T>(R));
  }
}

template <typename T>
void parity(double tol) {
  if (cuda::queryDevices().device_count == 0) GTEST_SKIP() << "no CUDA device";
  const Fixture& f = fixture();
  const SkinArrays<T> arr = skinArrays<T>(f.binding);
  cuda::SkinningCuda<T> gpu;
  gpu.upload(arr.view(), int(arr.rest_centres.size()), arr.triangles, arr.tri_offsets, arr.tri_of_vertex);
  const int nv = arr.view().vertex_count;
  std::vector<Vec3<T>> centres;
  std::vector<Mat3<T>> rots;
  std::vector<Vec3<T>> cpu_x(static_cast<std::size_t>(nv)), cpu_n(static_cast<std::size_t>(nv)), gpu_x, gpu_n;
  for (int frame = 0; frame < 100; ++frame) {  // 100 frames of a growing twist
    twist<T>(f.pack.model, centres, rots, 0.01 * frame);
    cpu::skinSurfaceCpu(arr.view(), centres.data(), rots.data(), cpu_x.data());
    gpu.deformHost(centres.data(), rots.data(), gpu_x, &gpu_n);
  }
  cpu::vertexNormalsCpu(nv, cpu_x.data(), arr.triangles.data(), arr.tri_offsets.data(), arr.tri_of_vertex.data(),
                        cpu_n.data());
  ASSERT_EQ(gpu_x.size(), cpu_x.size());
  for (int v = 0; v < nv; ++v) {
    EXPECT_LE(norm(Vec3d(gpu_x[std::size_t(v)]) - Vec3d(cpu_x[std::size_t(v)])), tol * 0.2) << v;  // 0.2 m organ
    EXPECT_LE(norm(Vec3d(gpu_n[std::size_t(v)]) - Vec3d(cpu_n[std::size_t(v)])), 100.0 * tol) << v;
  }
}

// Same formula, same order of operations: agreement to a few ulps (FMA contraction may differ).
TEST(SkinningGpu, MatchesCpuFloat) { parity<float>(1e-6); }
TEST(SkinningGpu, MatchesCpuDouble) { parity<double>(1e-14); }

TEST(SkinningGpu, RestAndRigidMotionExact) {
  if (cuda::queryDevices().device_count == 0) GTEST_SKIP() << "no CUDA device";
  const Fixture& f = fixture();
  const SkinArrays<float> arr = skinArrays<float>(f.binding);
  cuda::SkinningCuda<float> gpu;
  gpu.upload(arr.view(), int(arr.rest_centres.size()), arr.triangles, arr.tri_offsets, arr.tri_of_vertex);
  std::vector<Vec3f> x;
  gpu.deformHost(arr.rest_centres.data(), nullptr, x);
  for (std::size_t v = 0; v < x.size(); ++v) EXPECT_LE(norm(Vec3d(x[v]) - f.mesh.vertices[v]), 1e-6 * 0.2);
  const double a = 0.7;
  const Mat3d R = Mat3d::fromRows({std::cos(a), -std::sin(a), 0}, {std::sin(a), std::cos(a), 0}, {0, 0, 1});
  const Vec3d t{0.1, 0.2, -0.05};
  std::vector<Vec3f> centres;
  for (const auto& c : f.pack.model.rest_centers) centres.push_back(Vec3f(R * c + t));
  std::vector<Mat3f> rots(centres.size(), Mat3f(R));
  gpu.deformHost(centres.data(), rots.data(), x);
  for (std::size_t v = 0; v < x.size(); ++v) EXPECT_LE(norm(Vec3d(x[v]) - (R * f.mesh.vertices[v] + t)), 1e-6 * 0.2);
}

// Rotations handed over as the PBD state's quaternions give the same skin as the matrices on the CPU.
TEST(SkinningGpu, QuaternionRotationsMatchCpu) {
  if (cuda::queryDevices().device_count == 0) GTEST_SKIP() << "no CUDA device";
  const Fixture& f = fixture();
  const SkinArrays<double> arr = skinArrays<double>(f.binding);
  cuda::SkinningCuda<double> gpu;
  gpu.upload(arr.view(), int(arr.rest_centres.size()), arr.triangles, arr.tri_offsets, arr.tri_of_vertex);
  const int n = int(f.pack.model.size());
  std::vector<pbd::Quat<double>> q(static_cast<std::size_t>(n));
  std::vector<Vec3d> centres;
  for (int i = 0; i < n; ++i) {
    q[std::size_t(i)] = pbd::quatFromAxisAngle(Vec3d{0.0, 0.6, 0.8}, 0.01 * i);
    centres.push_back(f.pack.model.rest_centers[std::size_t(i)] + Vec3d{0.001 * i, 0.0, 0.0});
  }
  std::vector<Mat3d> mats(static_cast<std::size_t>(n));
  cpu::quatsToMatricesCpu(n, q.data(), mats.data());
  std::vector<Vec3d> cpu_x(arr.rest_vertices.size());
  cpu::skinSurfaceCpu(arr.view(), centres.data(), mats.data(), cpu_x.data());
  cuda::DeviceBuffer<Vec3d> dc;
  cuda::DeviceBuffer<pbd::Quat<double>> dq;
  dc.upload(centres);
  dq.upload(q);
  gpu.deformDeviceFromQuats(dc.data(), dq.data());
  ASSERT_EQ(cudaDeviceSynchronize(), cudaSuccess);
  std::vector<Vec3d> gpu_x(cpu_x.size());
  INC_CUDA(cudaMemcpy(gpu_x.data(), gpu.positions(), gpu_x.size() * sizeof(Vec3d), cudaMemcpyDeviceToHost));
  for (std::size_t v = 0; v < gpu_x.size(); ++v) EXPECT_LE(norm(gpu_x[v] - cpu_x[v]), 1e-14) << v;
}

// Rotation estimate + skinning on the device equals the CPU path (float, 100 frames of a growing twist with
// warm-started quaternions, 2 iterations per frame).
TEST(SkinningGpu, EstimatedRotationsMatchCpu) {
  if (cuda::queryDevices().device_count == 0) GTEST_SKIP() << "no CUDA device";
  const Fixture& f = fixture();
  const SkinArrays<float> arr = skinArrays<float>(f.binding);
  const auto nb = sphereNeighbourhoods<float>(f.pack.model);
  cuda::SkinningCuda<float> gpu;
  gpu.upload(arr.view(), int(arr.rest_centres.size()), arr.triangles, arr.tri_offsets, arr.tri_of_vertex);
  gpu.uploadNeighbourhoods(nb.offsets, nb.neighbours, nb.masses);
  const int n = int(f.pack.model.size());
  std::vector<pbd::Quat<float>> q(static_cast<std::size_t>(n));
  std::vector<Mat3f> cpu_r(static_cast<std::size_t>(n)), gpu_r, ignored;
  std::vector<Vec3f> centres, cpu_x(arr.rest_vertices.size()), gpu_x;
  for (int frame = 0; frame < 100; ++frame) {
    twist<float>(f.pack.model, centres, ignored, 0.01 * frame);
    cpu::sphereRotationsCpu(n, centres.data(), nb.rest_centres.data(), nb.masses.data(), nb.offsets.data(),
                            nb.neighbours.data(), 2, q.data(), cpu_r.data());
    gpu.deformWithEstimatedRotationsHost(centres.data(), 2, gpu_x, &gpu_r);
  }
  cpu::skinSurfaceCpu(arr.view(), centres.data(), cpu_r.data(), cpu_x.data());
  // Float rounding (FMA contraction differs between nvcc and g++) is amplified by the polar iteration in nearly
  // flat neighbourhoods; a wrong kernel gives O(1) differences.
  for (int i = 0; i < n; ++i)
    EXPECT_LE(frobeniusNorm(Mat3d(gpu_r[std::size_t(i)]) - Mat3d(cpu_r[std::size_t(i)])), 5e-4) << i;
  for (std::size_t v = 0; v < cpu_x.size(); ++v) EXPECT_LE(norm(Vec3d(gpu_x[v]) - Vec3d(cpu_x[v])), 1e-4 * 0.2) << v;
}

}  // namespace
}  // namespace inc
#endif  // INCISION_HAVE_CUDA
