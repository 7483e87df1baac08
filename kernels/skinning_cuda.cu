// CUDA kernels for skinning (linear blend of sphere motions, area-weighted vertex normals); gather, no atomics.
#include "kernels/skinning_cuda.h"

#include <stdexcept>

#include "kernels/cuda_check.h"
#include "kernels/device_buffer.h"

namespace inc::cuda {
namespace {

constexpr int kBlock = 256;

template <typename T>
__global__ void skinKernel(skin::SkinView<T> view, const Vec3<T>* centres, const Mat3<T>* rotations, Vec3<T>* out) {
  const int v = blockIdx.x * blockDim.x + threadIdx.x;
  if (v >= view.vertex_count) return;
  out[v] = skin::skinVertex(view, v, centres, rotations);
}

template <typename T>
__global__ void normalKernel(int n, const Vec3<T>* x, const std::int32_t* tris, const std::int32_t* off,
                             const std::int32_t* tri_of, Vec3<T>* normals) {
  const int v = blockIdx.x * blockDim.x + threadIdx.x;
  if (v >= n) return;
  normals[v] = skin::vertexNormal(v, x, tris, off, tri_of);
}

template <typename T>
__global__ void rotationKernel(int n, const Vec3<T>* x, const Vec3<T>* x0, const T* mass, const std::int32_t* off,
                               const std::int32_t* nbr, int iterations, pbd::Quat<T>* quats, Mat3<T>* rotations) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const pbd::Quat<T> q = skin::sphereRotation(i, x, x0, mass, off, nbr, quats[i], iterations);
  quats[i] = q;
  rotations[i] = pbd::quatToMatrix(q);
}

template <typename T>
__global__ void quatKernel(int n, const pbd::Quat<T>* quats, Mat3<T>* rotations) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  rotations[i] = pbd::quatToMatrix(quats[i]);
}

int blocks(int n) { return (n + kBlock - 1) / kBlock; }

}  // namespace

template <typename T>
struct SkinningCuda<T>::Impl {
  int vertex_count = 0, k = 0, sphere_count = 0;
  DeviceBuffer<Vec3<T>> rest_vertices, rest_centres, positions, normals, centres;
  DeviceBuffer<Mat3<T>> rotations, estimated;
  DeviceBuffer<pbd::Quat<T>> quats;
  DeviceBuffer<std::int32_t> nbr_offsets, nbr;
  DeviceBuffer<T> masses;
  DeviceBuffer<std::int32_t> sphere, triangles, tri_offsets, tri_of_vertex;
  DeviceBuffer<T> weight;
  skin::SkinView<T> view() const {
    skin::SkinView<T> s;
    s.vertex_count = vertex_count;
    s.k = k;
    s.rest_vertices = rest_vertices.data();
    s.sphere = sphere.data();
    s.weight = weight.data();
    s.rest_centres = rest_centres.data();
    return s;
  }
};

template <typename T>
SkinningCuda<T>::SkinningCuda() : impl_(std::make_unique<Impl>()) {}
template <typename T>
SkinningCuda<T>::~SkinningCuda() = default;

template <typename T>
void SkinningCuda<T>::upload(const skin::SkinView<T>& h, int sphere_count, const std::vector<std::int32_t>& triangles,
                             const std::vector<std::int32_t>& tri_offsets,
                             const std::vector<std::int32_t>& tri_of_vertex) {
  if (h.vertex_count < 0 || h.k < 1 || sphere_count < 1)
    throw std::invalid_argument("SkinningCuda::upload: empty binding");
  if (!tri_offsets.empty() && tri_offsets.size() != std::size_t(h.vertex_count) + 1)
    throw std::invalid_argument("SkinningCuda::upload: tri_offsets must have vertex_count + 1 entries");
  Impl& m = *impl_;
  m.vertex_count = h.vertex_count;
  m.k = h.k;
  m.sphere_count = sphere_count;
  const std::size_t slots = std::size_t(h.vertex_count) * std::size_t(h.k);
  m.rest_vertices.upload(h.rest_vertices, std::size_t(h.vertex_count));
  m.rest_centres.upload(h.rest_centres, std::size_t(sphere_count));
  m.sphere.upload(h.sphere, slots);
  m.weight.upload(h.weight, slots);
  m.triangles.upload(triangles);
  m.tri_offsets.upload(tri_offsets);
  m.tri_of_vertex.upload(tri_of_vertex);
  m.positions.resize(std::size_t(h.vertex_count));
  m.normals.resize(std::size_t(h.vertex_count));
  m.centres.resize(std::size_t(sphere_count));
  m.rotations.resize(std::size_t(sphere_count));
}

template <typename T>
void SkinningCuda<T>::deformDevice(const Vec3<T>* d_centres, const Mat3<T>* d_rotations, void* stream) {
  Impl& m = *impl_;
  if (m.vertex_count == 0) return;
  skinKernel<T><<<blocks(m.vertex_count), kBlock, 0, static_cast<cudaStream_t>(stream)>>>(
      m.view(), d_centres, d_rotations, m.positions.data());
  INC_CUDA_LAUNCH("skinKernel");
}

template <typename T>
void SkinningCuda<T>::deformDeviceFromQuats(const Vec3<T>* d_centres, const pbd::Quat<T>* d_quats, void* stream) {
  Impl& m = *impl_;
  if (m.vertex_count == 0) return;
  quatKernel<T><<<blocks(m.sphere_count), kBlock, 0, static_cast<cudaStream_t>(stream)>>>(m.sphere_count, d_quats,
                                                                                          m.rotations.data());
  INC_CUDA_LAUNCH("quatKernel");
  deformDevice(d_centres, m.rotations.data(), stream);
}

template <typename T>
void SkinningCuda<T>::normalsDevice(void* stream) {
  Impl& m = *impl_;
  if (m.vertex_count == 0) return;
  if (m.tri_offsets.size() != std::size_t(m.vertex_count) + 1)
    throw std::logic_error("SkinningCuda::normalsDevice: no triangle adjacency uploaded");
  normalKernel<T><<<blocks(m.vertex_count), kBlock, 0, static_cast<cudaStream_t>(stream)>>>(
      m.vertex_count, m.positions.data(), m.triangles.data(), m.tri_offsets.data(), m.tri_of_vertex.data(),
      m.normals.data());
  INC_CUDA_LAUNCH("normalKernel");
}

template <typename T>
void SkinningCuda<T>::uploadNeighbourhoods(const std::vector<std::int32_t>& offsets,
                                           const std::vector<std::int32_t>& neighbours, const std::vector<T>& masses) {
  Impl& m = *impl_;
  if (offsets.size() != std::size_t(m.sphere_count) + 1 || masses.size() != std::size_t(m.sphere_count))
    throw std::invalid_argument("SkinningCuda::uploadNeighbourhoods: sizes do not match the uploaded spheres");
  m.nbr_offsets.upload(offsets);
  m.nbr.upload(neighbours);
  m.masses.upload(masses);
  const std::vector<pbd::Quat<T>> identity(std::size_t(m.sphere_count));
  m.quats.upload(identity);
  m.estimated.resize(std::size_t(m.sphere_count));
}

template <typename T>
void SkinningCuda<T>::estimateRotationsDevice(const Vec3<T>* d_centres, int iterations, void* stream) {
  Impl& m = *impl_;
  if (m.nbr_offsets.size() != std::size_t(m.sphere_count) + 1)
    throw std::logic_error("SkinningCuda::estimateRotationsDevice: no neighbourhoods uploaded");
  rotationKernel<T><<<blocks(m.sphere_count), kBlock, 0, static_cast<cudaStream_t>(stream)>>>(
      m.sphere_count, d_centres, m.rest_centres.data(), m.masses.data(), m.nbr_offsets.data(), m.nbr.data(), iterations,
      m.quats.data(), m.estimated.data());
  INC_CUDA_LAUNCH("rotationKernel");
}

template <typename T>
const Mat3<T>* SkinningCuda<T>::rotations() const {
  return impl_->estimated.data();
}

template <typename T>
void SkinningCuda<T>::deformWithEstimatedRotationsHost(const Vec3<T>* centres, int iterations,
                                                       std::vector<Vec3<T>>& positions_out,
                                                       std::vector<Mat3<T>>* rotations_out) {
  Impl& m = *impl_;
  m.centres.upload(centres, std::size_t(m.sphere_count));
  estimateRotationsDevice(m.centres.data(), iterations);
  deformDevice(m.centres.data(), m.estimated.data());
  INC_CUDA(cudaDeviceSynchronize());  // the results are read on the host next
  positions_out.resize(std::size_t(m.vertex_count));
  m.positions.download(positions_out.data(), positions_out.size());
  if (rotations_out) {
    rotations_out->resize(std::size_t(m.sphere_count));
    m.estimated.download(rotations_out->data(), rotations_out->size());
  }
}

template <typename T>
const Vec3<T>* SkinningCuda<T>::positions() const {
  return impl_->positions.data();
}
template <typename T>
const Vec3<T>* SkinningCuda<T>::normals() const {
  return impl_->normals.data();
}
template <typename T>
int SkinningCuda<T>::vertexCount() const {
  return impl_->vertex_count;
}
template <typename T>
int SkinningCuda<T>::sphereCount() const {
  return impl_->sphere_count;
}

template <typename T>
void SkinningCuda<T>::deformHost(const Vec3<T>* centres, const Mat3<T>* rotations, std::vector<Vec3<T>>& positions_out,
                                 std::vector<Vec3<T>>* normals_out) {
  Impl& m = *impl_;
  m.centres.upload(centres, std::size_t(m.sphere_count));
  if (rotations) m.rotations.upload(rotations, std::size_t(m.sphere_count));
  deformDevice(m.centres.data(), rotations ? m.rotations.data() : nullptr);
  if (normals_out) normalsDevice();
  INC_CUDA(cudaDeviceSynchronize());  // the results are read on the host next
  positions_out.resize(std::size_t(m.vertex_count));
  m.positions.download(positions_out.data(), positions_out.size());
  if (normals_out) {
    normals_out->resize(std::size_t(m.vertex_count));
    m.normals.download(normals_out->data(), normals_out->size());
  }
}

template class SkinningCuda<float>;
template class SkinningCuda<double>;

}  // namespace inc::cuda
