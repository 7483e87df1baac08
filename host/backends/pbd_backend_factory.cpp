// PBD backend factory: the CPU fallback or CUDA, per the resolved backend kind.
#include "host/backends/solver_factory.h"

#include "cpu_fallback/pbd_solver_cpu.h"
#include "host/backends/backend_choice.h"
#include "model/pbd_model.h"
#if INCISION_HAVE_CUDA
#include "kernels/pbd_solver_cuda.h"
#endif

namespace inc {

template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdBackend(BackendKind kind) {
  const BackendChoice choice = resolveBackend(kind);
#if INCISION_HAVE_CUDA
  if (choice.kind == BackendKind::Cuda) return cuda::makePbdCudaBackend<T>();
#endif
  return cpu::makePbdCpuBackend<T>();
}

template std::unique_ptr<PbdBackend<float>> makePbdBackend<float>(BackendKind);
template std::unique_ptr<PbdBackend<double>> makePbdBackend<double>(BackendKind);

}  // namespace inc
