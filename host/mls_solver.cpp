// MLS solver factory: builds the model in the requested precision and picks the CPU or CUDA backend.
#include "host/mls_solver.h"

#include "cpu_fallback/mls_solver_cpu.h"
#if INCISION_HAVE_CUDA
#include "kernels/mls_solver_cuda.h"
#endif

namespace inc {

void MlsSolver::positions(std::vector<Vec3d>& out) const {
  displacements(out);
  const std::vector<Vec3d> rest = restPositions();
  for (std::size_t i = 0; i < out.size(); ++i) out[i] += rest[i];
}

std::unique_ptr<MlsSolver> makeMlsSolver(const MlsBuildInput& input, BackendKind backend, Precision precision) {
  const BackendChoice choice = resolveBackend(backend);
  const bool f64 = precision == Precision::Float64;
  if (choice.kind == BackendKind::Cuda) {
#if INCISION_HAVE_CUDA
    return f64 ? cuda::makeMlsSolverCuda(buildMlsModel<double>(input)) : cuda::makeMlsSolverCuda(buildMlsModel<float>(input));
#endif
  }
  return f64 ? cpu::makeMlsSolverCpu(buildMlsModel<double>(input)) : cpu::makeMlsSolverCpu(buildMlsModel<float>(input));
}

}  // namespace inc
