// CUDA skinning: the binding resident on the device, one thread per vertex for the blend and for the normals.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "physics/skinning.h"

namespace inc::cuda {

template <typename T>
class SkinningCuda {
 public:
  SkinningCuda();
  ~SkinningCuda();
  SkinningCuda(const SkinningCuda&) = delete;
  SkinningCuda& operator=(const SkinningCuda&) = delete;

  // Uploads a binding (host arrays as in SkinArrays<T>): `sphere_count` rest centres, k slots per vertex.
  void upload(const skin::SkinView<T>& host_view, int sphere_count, const std::vector<std::int32_t>& triangles,
              const std::vector<std::int32_t>& tri_offsets, const std::vector<std::int32_t>& tri_of_vertex);

  // Device-resident path (no host synchronisation): centres and optional rotations are device pointers of
  // sphere_count entries; results stay on the device (positions(), normals()). `stream` is a cudaStream_t.
  void deformDevice(const Vec3<T>* d_centres, const Mat3<T>* d_rotations, void* stream = nullptr);
  // The same with rotations given as quaternions (the PBD state's per-particle rotations, device pointer):
  // converted into an internal matrix buffer first.
  void deformDeviceFromQuats(const Vec3<T>* d_centres, const pbd::Quat<T>* d_quats, void* stream = nullptr);
  void normalsDevice(void* stream = nullptr);
  const Vec3<T>* positions() const;
  const Vec3<T>* normals() const;

  // Host convenience for tests and benchmarks: copies centres (and rotations, may be null) in, runs
  // deformDevice (and normalsDevice when `normals_out` is given), copies the results out (synchronises).
  void deformHost(const Vec3<T>* centres, const Mat3<T>* rotations, std::vector<Vec3<T>>& positions_out,
                  std::vector<Vec3<T>>* normals_out = nullptr);

  // Per-sphere rotation estimate (skin::sphereRotation) on the device: upload the link neighbourhoods once per
  // topology (CSR offsets/neighbours, masses; rest centres come from upload()), then each frame
  // estimateRotationsDevice(centres) updates the warm-started quaternions and rotations() (device, Mat3 per
  // sphere), ready for deformDevice(centres, rotations()).
  void uploadNeighbourhoods(const std::vector<std::int32_t>& offsets, const std::vector<std::int32_t>& neighbours,
                            const std::vector<T>& masses);
  void estimateRotationsDevice(const Vec3<T>* d_centres, int iterations, void* stream = nullptr);
  const Mat3<T>* rotations() const;
  // Host convenience: estimate from host centres, deform with those rotations, copy positions (and rotations).
  void deformWithEstimatedRotationsHost(const Vec3<T>* centres, int iterations, std::vector<Vec3<T>>& positions_out,
                                        std::vector<Mat3<T>>* rotations_out = nullptr);

  int vertexCount() const;
  int sphereCount() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace inc::cuda
