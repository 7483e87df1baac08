// MLS solver factory: builds the model in the requested precision and picks the CPU or CUDA backend.
#include "host/backends/solver_factory.h"

#include <chrono>
#include <utility>

#include "base/elapsed_ms.h"
#include "cpu_fallback/mls_solver_cpu.h"
#include "host/assembly/mls_model_build.h"
#include "host/backends/backend_choice.h"
#if INCISION_HAVE_CUDA
#include "kernels/mls_solver_cuda.h"
#endif

namespace inc {

std::unique_ptr<MlsSolver> makeMlsSolver(const MlsBuildInput& input, BackendKind backend, Precision precision) {
  resolveBackend(backend);  // an unusable backend is refused before the build
  MlsBuiltModel m = buildMlsModelIn(input, precision);
  std::unique_ptr<MlsSolver> solver;
  loadMlsSolver(solver, m, backend);
  return solver;
}

MlsBuiltModel buildMlsModelIn(const MlsBuildInput& input, Precision precision) {
  MlsBuiltModel m;
  m.precision = precision;
  if (precision == Precision::Float64)
    m.f64 = buildMlsModel<double>(input);
  else
    m.f32 = buildMlsModel<float>(input);
  return m;
}

void loadMlsSolver(std::unique_ptr<MlsSolver>& solver, MlsBuiltModel& model, BackendKind backend) {
  const BackendKind kind = resolveBackend(backend).kind;
  const bool f64 = model.precision == Precision::Float64;
  // Only the CUDA solver reuses anything (its device buffers, stream and graph).
  if (solver && kind == BackendKind::Cuda && solver->backend() == kind && solver->precision() == model.precision &&
      (f64 ? solver->replaceModel(model.f64) : solver->replaceModel(model.f32)))
    return;
  solver.reset();  // free the old solver's device memory before the new one allocates
  if (kind == BackendKind::Cuda) {
#if INCISION_HAVE_CUDA
    solver = f64 ? cuda::makeMlsSolverCuda(std::move(model.f64)) : cuda::makeMlsSolverCuda(std::move(model.f32));
    return;
#endif
  }
  solver = f64 ? cpu::makeMlsSolverCpu(std::move(model.f64)) : cpu::makeMlsSolverCpu(std::move(model.f32));
}

void rebuildMlsSolver(std::unique_ptr<MlsSolver>& solver, const MlsBuildInput& input, BackendKind backend,
                      Precision precision, double* build_ms) {
  const auto t0 = std::chrono::steady_clock::now();
  MlsBuiltModel m = buildMlsModelIn(input, precision);
  if (build_ms) *build_ms = msSince(t0);
  loadMlsSolver(solver, m, backend);
}

}  // namespace inc
