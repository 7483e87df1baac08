// Tearing step factory: the CPU step (cpu::tearStepCpu behind the TearStepBackend interface) or the CUDA one.
#include "host/backends/solver_factory.h"

#include "cpu_fallback/tearing_cpu.h"
#include "host/backends/backend_choice.h"
#if INCISION_HAVE_CUDA
#include "kernels/tearing_cuda.h"
#endif

namespace inc {

namespace {
template <typename T>
class TearStepCpu final : public TearStepBackend<T> {
 public:
  BackendKind kind() const override { return BackendKind::Cpu; }
  int step(TearSheet<T>& s, const TearParams<T>& p, TearFrameStats& st) override {
    const TearStepStats r = cpu::tearStepCpu<T>(s, p, nullptr, false);  // the driver rebuilds
    st.splits += r.splits;
    st.yielding += r.yielding;
    st.deferred += r.deferred;
    return r.splits;
  }
};
}  // namespace

template <typename T>
std::unique_ptr<TearStepBackend<T>> makeTearStepBackend(BackendKind kind) {
  const BackendChoice choice = resolveBackend(kind);
#if INCISION_HAVE_CUDA
  if (choice.kind == BackendKind::Cuda) return cuda::makeTearStepCuda<T>();
#endif
  (void)choice;
  return std::make_unique<TearStepCpu<T>>();
}

template std::unique_ptr<TearStepBackend<float>> makeTearStepBackend<float>(BackendKind);
template std::unique_ptr<TearStepBackend<double>> makeTearStepBackend<double>(BackendKind);

}  // namespace inc
