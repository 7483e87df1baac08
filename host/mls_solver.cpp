// MLS solver factory: builds the model in the requested precision and picks the CPU or CUDA backend.
#include "host/mls_solver.h"

#include "cpu_fallback/mls_solver_cpu.h"

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
    // The CUDA MLS solver is not written yet: refuse rather than silently run on the CPU.
    if (backend == BackendKind::Cuda)
      throw InputError(input.source, "solver.backend", "the MLS solver has no CUDA backend yet; use \"cpu\"");
  }
  return f64 ? cpu::makeMlsSolverCpu(buildMlsModel<double>(input)) : cpu::makeMlsSolverCpu(buildMlsModel<float>(input));
}

}  // namespace inc
