// The stability matrix on the CUDA backend: the same cases as tests/sim/test_stability_matrix.cpp (skip without a GPU).
#include <gtest/gtest.h>

#if INCISION_HAVE_CUDA
#include "kernels/device_info.h"
#include "tests/support/stability_matrix.h"

using namespace inc;
using namespace inc::stability;

namespace {
bool noDevice() { return cuda::queryDevices().device_count == 0; }
}  // namespace

#define INC_GPU_CASE(name, call)                      \
  TEST(StabilityMatrixGpu, name) {                    \
    if (noDevice()) GTEST_SKIP() << "no CUDA device"; \
    call;                                             \
  }

INC_GPU_CASE(MlsExtremeMaterials, materialsCase(BackendKind::Cuda, true))
INC_GPU_CASE(PbdExtremeMaterials, materialsCase(BackendKind::Cuda, false))
INC_GPU_CASE(MlsTimeStepUpToTwiceTheLimitIsStableOrRefused, mlsTimeStepCase(BackendKind::Cuda))
INC_GPU_CASE(PbdLargeTimeStepsStayBounded, pbdTimeStepCase(BackendKind::Cuda))
INC_GPU_CASE(PbdLongFrameRefusedOrAutoSubstepped, pbdLongSubstepCase(BackendKind::Cuda))
INC_GPU_CASE(MlsCoarseToFineSpacing, spacingCase(BackendKind::Cuda, true))
INC_GPU_CASE(PbdCoarseToFineSpacing, spacingCase(BackendKind::Cuda, false))
INC_GPU_CASE(MlsJitteredRestPositions, jitterCase(BackendKind::Cuda, true))
INC_GPU_CASE(PbdJitteredRestPositions, jitterCase(BackendKind::Cuda, false))
INC_GPU_CASE(MlsCompressionUntilNeighbourhoodsInvertIsFiniteOrGuarded, compressionCase(BackendKind::Cuda, true))
INC_GPU_CASE(PbdCompressionUntilNeighbourhoodsInvertIsFiniteOrGuarded, compressionCase(BackendKind::Cuda, false))
INC_GPU_CASE(MlsIsolatedParticleFallsFreely, mlsIsolatedCase(BackendKind::Cuda))
INC_GPU_CASE(PbdIsolatedSphereFallsFreely, pbdIsolatedCase(BackendKind::Cuda))
// The soak on the GPU: 1e5 PBD frames / 2500 MLS frames (~1e5 substeps) within 60 s of wall time each.
INC_GPU_CASE(MlsSoak, soakCase(BackendKind::Cuda, true, 60.0, 100000 / 40))
INC_GPU_CASE(PbdSoak, soakCase(BackendKind::Cuda, false, 60.0, 100000))
#endif  // INCISION_HAVE_CUDA
