// CPU skinning loops over the shared physics/skinning.h math (same functions and arguments as the CUDA kernels).
#include "cpu_fallback/skinning_cpu.h"

#include "base/parallel.h"

namespace inc::cpu {

template <typename T>
void skinSurfaceCpu(const skin::SkinView<T>& view, const Vec3<T>* centres, const Mat3<T>* rotations, Vec3<T>* out) {
  parallelFor(view.vertex_count, [&](std::int64_t v) { out[v] = skin::skinVertex(view, int(v), centres, rotations); });
}

template <typename T>
void vertexNormalsCpu(int vertex_count, const Vec3<T>* x, const std::int32_t* triangles,
                      const std::int32_t* tri_offsets, const std::int32_t* tri_of_vertex, Vec3<T>* normals) {
  parallelFor(vertex_count, [&](std::int64_t v) {
    normals[v] = skin::vertexNormal(int(v), x, triangles, tri_offsets, tri_of_vertex);
  });
}

template <typename T>
void sphereRotationsCpu(int sphere_count, const Vec3<T>* x, const Vec3<T>* x0, const T* mass, const std::int32_t* off,
                        const std::int32_t* nbr, int iterations, pbd::Quat<T>* quats, Mat3<T>* rotations) {
  parallelFor(sphere_count, [&](std::int64_t i) {
    quats[i] = skin::sphereRotation(int(i), x, x0, mass, off, nbr, quats[i], iterations);
    rotations[i] = pbd::quatToMatrix(quats[i]);
  });
}

template <typename T>
void quatsToMatricesCpu(int n, const pbd::Quat<T>* quats, Mat3<T>* rotations) {
  parallelFor(n, [&](std::int64_t i) { rotations[i] = pbd::quatToMatrix(quats[i]); });
}

template void quatsToMatricesCpu<float>(int, const pbd::Quat<float>*, Mat3<float>*);
template void quatsToMatricesCpu<double>(int, const pbd::Quat<double>*, Mat3<double>*);
template void sphereRotationsCpu<float>(int, const Vec3<float>*, const Vec3<float>*, const float*, const std::int32_t*,
                                        const std::int32_t*, int, pbd::Quat<float>*, Mat3<float>*);
template void sphereRotationsCpu<double>(int, const Vec3<double>*, const Vec3<double>*, const double*,
                                         const std::int32_t*, const std::int32_t*, int, pbd::Quat<double>*,
                                         Mat3<double>*);
template void skinSurfaceCpu<float>(const skin::SkinView<float>&, const Vec3<float>*, const Mat3<float>*, Vec3<float>*);
template void skinSurfaceCpu<double>(const skin::SkinView<double>&, const Vec3<double>*, const Mat3<double>*,
                                     Vec3<double>*);
template void vertexNormalsCpu<float>(int, const Vec3<float>*, const std::int32_t*, const std::int32_t*,
                                      const std::int32_t*, Vec3<float>*);
template void vertexNormalsCpu<double>(int, const Vec3<double>*, const std::int32_t*, const std::int32_t*,
                                       const std::int32_t*, Vec3<double>*);

}  // namespace inc::cpu
